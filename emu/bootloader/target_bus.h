// What the bootloader's monitor reaches: the chip's memory map as the CPU sees it. The monitor
// runs on the chip, so every read and write it executes for bossac (a register of NVMCTRL, the
// page buffer, RAM, the DSU's device id, the SCB) goes through here and meets the chip's rules.
#pragma once

#include <cstdint>
#include <string>

namespace hmc::emu {

class TargetBus {
public:
  virtual ~TargetBus() = default;
  // A read or write of 1, 2 or 4 bytes. False when nothing answers at `address` (a bus error on
  // the chip); `error` then says what and where.
  virtual bool read(uint32_t address, unsigned size, uint32_t& value, std::string& error) = 0;
  virtual bool write(uint32_t address, uint32_t value, unsigned size, std::string& error) = 0;
};

}  // namespace hmc::emu
