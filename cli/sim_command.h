// `hmc sim`: start the simulated board (hmc-sim) on TCP or a pseudo-terminal and say how to
// connect to it (docs/cli.md, docs/sim.md).
#pragma once

#include <CLI/CLI.hpp>

namespace hmc::cli {

// Adds `sim` to `app`; its outcome is written to `exit_code`.
void add_sim_command(CLI::App& app, int& exit_code);

}  // namespace hmc::cli
