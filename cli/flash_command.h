// `hmc flash [FILE]`: put the firmware on a SAMD21 board with bossac (native USB bootloader),
// OpenOCD (SWD probe) or by copying a UF2 file to the bootloader's USB drive (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

namespace hmc::cli {

// Adds `flash` to `app`; its outcome is written to `exit_code`.
void add_flash_command(CLI::App& app, int& exit_code);

}  // namespace hmc::cli
