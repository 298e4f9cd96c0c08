// `hmc jog`: the board's steppers moved from the keyboard in a raw terminal — arrows and Page
// Up/Down by the current step (Shift: 10x), +/- change the step, space stops everything, z
// zeroes the axis last moved (POS, protocol 6), q quits; soft limits stop a jog at the limit, the
// terminal is restored and every motor stopped on every way out (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

void add_jog_command(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
