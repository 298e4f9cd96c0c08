// A raw flash image (.bin: the bytes objcopy writes, no symbols) as the emulator's image, so
// hmc-emu runs what the hmc-firmware package installs (hmc-firmware.bin, the application at
// 0x2000 behind the bootloader; hmc-firmware-nobl.bin at 0x0). Without symbols, messages name
// the program counter by address only.
#pragma once

#include <cstdint>
#include <string>

#include "elf/elf_image.h"

namespace hmc::emu {

// True when `path` names a raw image (ends in .bin).
bool is_raw_image(const std::string& path);

// Loads the file's bytes at `base`; false with `error` naming the file on failure (missing,
// unreadable, empty, or beyond the 256 KB flash).
bool load_raw_image(const std::string& path, uint32_t base, ElfImage& image, std::string& error);

}  // namespace hmc::emu
