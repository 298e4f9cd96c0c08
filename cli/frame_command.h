// `hmc frame encode|decode|check`: the codec at the command line.
#pragma once

#include <CLI/CLI.hpp>

namespace hmc::cli {

// Adds `frame` and its subcommands to `app`; their outcome is written to `exit_code`.
void add_frame_command(CLI::App& app, int& exit_code);

}  // namespace hmc::cli
