// The bootloader's flash routines, executed on the chip's bus the way a bootloader's code runs
// them (datasheet, NVMCTRL, "NVM Write" and "Erase Row"): ER per row; for a page, a manual page
// write: page buffer clear, 32-bit writes into the page buffer through the flash address space,
// WP. Each command writes ADDR in 16-bit words and CTRLA with the CMDEX key, waits for READY and
// checks ERROR. Shared by the SAM-BA monitor (X, Y) and the UF2 drive.
#pragma once

#include <cstdint>
#include <string>

#include "target_bus.h"

namespace hmc::emu {

class BootFlash {
public:
  explicit BootFlash(TargetBus& bus) : bus_(bus) {}

  // Each returns false with `error` set when the bus or NVMCTRL refused (LOCKE, PROGE...).
  bool erase_row(uint32_t address, std::string& error);
  // `words` holds the page's 16 words, little-endian as they go to the page buffer.
  bool write_page(uint32_t address, const uint32_t* words, std::string& error);

private:
  bool command(uint32_t byte_address, uint8_t command, std::string& error);

  TargetBus& bus_;
};

}  // namespace hmc::emu
