// `hmc grbl [--pty | --tcp HOST:PORT]`: the board as a grbl 1.1 controller, for G-code senders
// (CNCjs, bCNC, Universal Gcode Sender), over a pseudo-terminal or TCP (docs/grbl.md).
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

void add_grbl_command(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
