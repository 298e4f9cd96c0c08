// The bootloader's flash routines over NVMCTRL (boot_flash.h).
#include "boot_flash.h"

#include <cstdio>

#include "nvmctrl.h"

namespace hmc::emu {
namespace {

std::string hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

}  // namespace

bool BootFlash::command(uint32_t byte_address, uint8_t command, std::string& error) {
  constexpr uint32_t base = Nvmctrl::kBase;
  uint32_t flags = 0;
  if (!bus_.write(base + Nvmctrl::kAddr, byte_address / 2, 4, error) ||
      !bus_.write(base + Nvmctrl::kCtrlA, Nvmctrl::kCmdExKey << 8 | command, 2, error))
    return false;
  do {
    if (!bus_.read(base + Nvmctrl::kIntFlag, 1, flags, error)) return false;
  } while ((flags & Nvmctrl::kReady) == 0);
  if ((flags & Nvmctrl::kError) == 0) return true;
  uint32_t status = 0;
  std::string ignored;
  bus_.read(base + Nvmctrl::kStatus, 2, status, ignored);
  bus_.write(base + Nvmctrl::kStatus, status, 2, ignored);  // clear PROGE/LOCKE/NVME
  bus_.write(base + Nvmctrl::kIntFlag, Nvmctrl::kError, 1, ignored);
  const char* why = (status & Nvmctrl::kLockE) != 0   ? " (LOCKE: a locked region or the boot section)"
                    : (status & Nvmctrl::kProgE) != 0 ? " (PROGE)"
                                                      : "";
  error = "NVMCTRL command " + hex(command) + " at " + hex(byte_address) + " failed, STATUS " + hex(status) + why;
  return false;
}

bool BootFlash::erase_row(uint32_t address, std::string& error) { return command(address, Nvmctrl::kErase, error); }

bool BootFlash::write_page(uint32_t address, const uint32_t* words, std::string& error) {
  // Manual page write (CTRLB.MANW = 1): the WP command writes the page, not the last word.
  constexpr uint32_t ctrlb = Nvmctrl::kBase + Nvmctrl::kCtrlB;
  uint32_t value = 0;
  if (!bus_.read(ctrlb, 4, value, error) || !bus_.write(ctrlb, value | Nvmctrl::kManw, 4, error)) return false;
  if (!command(address, Nvmctrl::kPageBufferClear, error)) return false;
  for (uint32_t i = 0; i < Nvmctrl::kPageSize / 4; ++i)
    if (!bus_.write(address + 4 * i, words[i], 4, error)) return false;
  return command(address, Nvmctrl::kWritePage, error);
}

}  // namespace hmc::emu
