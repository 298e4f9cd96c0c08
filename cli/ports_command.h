// `hmc ports [--json]`: the serial ports this machine has, and which one is likely the board.
#pragma once

#include <CLI/CLI.hpp>

namespace hmc::cli {

// Adds `ports` to `app`; its outcome is written to `exit_code`.
void add_ports_command(CLI::App& app, int& exit_code);

}  // namespace hmc::cli
