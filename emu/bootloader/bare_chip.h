// The SAMD21 while its CPU sits in the bootloader, for running the monitor and the UF2 drive
// without the emulated CPU: the emulated chip (chip/chip.h: its peripherals, NVMCTRL with the
// NVM, the SCS with CPUID and AIRCR, the PM's bus clock masks) plus the 32 KB of RAM and the
// DSU's device id, which only the bootloader's host reads. An access nothing answers, or one the
// chip refuses (a masked bus clock, NVMCTRL's rules), fails with the reason. The chip keeps only
// its first violation, so after one the later refusals go unreported.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "chip/chip.h"
#include "nvmctrl.h"
#include "target_bus.h"

namespace hmc::emu {

class BareChip : public TargetBus {
public:
  // DSU DID: the register description's reset value 0x10010305 = ATSAMD21G18A, revision D.
  static constexpr uint32_t kDsuDid = 0x41002018;
  static constexpr uint32_t kDeviceId = 0x10010305;
  static constexpr uint32_t kRamBase = 0x20000000;
  static constexpr uint32_t kRamSize = 32 * 1024;

  BareChip();

  bool read(uint32_t address, unsigned size, uint32_t& value, std::string& error) override;
  bool write(uint32_t address, uint32_t value, unsigned size, std::string& error) override;

  Nvmctrl& nvm() { return chip_.nvmctrl(); }
  // True once software asked for a system reset (AIRCR written with VECTKEY and SYSRESETREQ).
  bool reset_requested() const { return chip_.reset_requested(); }
  void clear_reset_request() { chip_.clear_reset_request(); }
private:
  bool peripheral(uint32_t address) const;
  bool refused(std::string& error);

  Chip chip_;
  std::vector<uint8_t> ram_;
  std::string reported_;  // the chip's violation already handed out
};

}  // namespace hmc::emu
