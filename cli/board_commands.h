// `hmc send | move | home | stop | servo | led | status | monitor`: the commands that talk to a
// board through a session (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

// Adds the board commands to `app`; they read `global` and write their outcome to `exit_code`.
void add_board_commands(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
