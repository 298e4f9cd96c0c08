// `hmc zero AXIS [POSITION]`: tells the board that a resting motor is at 0 (or at POSITION, in
// the axis's units) from now on — POS, protocol 6 — so that a motor without switches can be
// given a reference, and its soft limits apply (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

void add_zero_command(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
