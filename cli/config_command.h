// `hmc config path | show | check [FILE]`: the machine profile — where it is looked for, what it
// says once read (each axis's steps per unit), and every mistake in it (docs/config.md).
#pragma once

#include <CLI/CLI.hpp>

#include "connection.h"

namespace hmc::cli {

void add_config_command(CLI::App& app, const GlobalOptions& global, int& exit_code);

}  // namespace hmc::cli
