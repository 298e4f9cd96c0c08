// The UF2 bootloader's USB drive, as a directory: it holds INFO_UF2.TXT and CURRENT.UF2 (the
// whole flash as UF2 blocks from 0x0) as the bootloader presents them, and takes a .uf2 file
// copied there the way the bootloader takes one (microsoft/uf2 README; the SAMD bootloader's
// rules): every block with the magics, a 256-byte payload at a row-aligned address at or above
// the application start 0x2000, and the SAMD21 family id (or none) is written into the flash
// through NVMCTRL (erase the row, write its four pages); other blocks are skipped. When a file
// has all the blocks it announces, the bootloader restarts into the application.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "boot_flash.h"
#include "target_bus.h"

namespace hmc::emu {

class Uf2Drive {
public:
  static constexpr uint32_t kAppStart = 0x2000;

  // `log` receives one line per file taken or refused.
  Uf2Drive(std::string directory, TargetBus& bus, std::function<void(const std::string&)> log);

  // Creates the directory's INFO_UF2.TXT and CURRENT.UF2 (from `flash`, the whole flash).
  bool present(const std::vector<uint8_t>& flash, std::string& error);

  // Looks for complete .uf2 files, writes their blocks and removes them. Returns true when a
  // whole file was flashed: the bootloader then resets into the application.
  bool poll();

  // Writes one UF2 file's blocks; returns the number of blocks written (`error` set when a
  // block's write failed, which stops the file).
  static size_t flash_file(const std::vector<uint8_t>& file, BootFlash& flash, std::string& error,
                           const std::function<void(const std::string&)>& log);

private:
  std::string directory_;
  BootFlash flash_;
  std::function<void(const std::string&)> log_;
};

}  // namespace hmc::emu
