// `hmc check | plan | run FILE`: motion files (docs/motion-files.md) validated, planned and run.
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

// Adds the motion-file commands to `app`; they read `global` and write their outcome to `exit_code`.
void add_motion_commands(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
