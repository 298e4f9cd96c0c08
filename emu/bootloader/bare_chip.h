// The memory map a SAMD21 shows while its CPU sits in the bootloader, for running the monitor
// and the UF2 drive without the emulated CPU: the NVM and NVMCTRL (nvmctrl.h), the 32 KB of RAM,
// the DSU's device id and the SCB's CPUID and AIRCR (whose SYSRESETREQ ends the bootloader).
// Everything else answers with a bus error naming the address. hmc-emu's full chip serves the
// same addresses through the same TargetBus interface.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nvmctrl.h"
#include "target_bus.h"

namespace hmc::emu {

class BareChip : public TargetBus {
public:
  // Identification (register description: DSU DID reset value 0x10010305 = ATSAMD21G18A,
  // revision D; ARM DDI0484C: the Cortex-M0+ r0p1 CPUID 0x410CC601).
  static constexpr uint32_t kDsuDid = 0x41002018;
  static constexpr uint32_t kDeviceId = 0x10010305;
  static constexpr uint32_t kCpuidAddress = 0xE000ED00;
  static constexpr uint32_t kCpuid = 0x410CC601;
  static constexpr uint32_t kAircr = 0xE000ED0C;
  static constexpr uint32_t kRamBase = 0x20000000;
  static constexpr uint32_t kRamSize = 32 * 1024;

  BareChip();

  bool read(uint32_t address, unsigned size, uint32_t& value, std::string& error) override;
  bool write(uint32_t address, uint32_t value, unsigned size, std::string& error) override;

  Nvmctrl& nvm() { return nvm_; }
  // True once software asked for a system reset (AIRCR written with VECTKEY and SYSRESETREQ).
  bool reset_requested() const { return reset_requested_; }
  // NVMCTRL's refusals since the last call.
  std::vector<std::string> take_violations();

private:
  std::vector<std::string> violations_;
  Nvmctrl nvm_;
  std::vector<uint8_t> ram_;
  bool reset_requested_ = false;
};

}  // namespace hmc::emu
