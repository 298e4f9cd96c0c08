// `hmc completion bash|zsh`: a shell completion script, written by walking the command line's own
// definition (its subcommands and options), so it can never list a command hmc does not have.
#pragma once

#include <CLI/CLI.hpp>

namespace hmc::cli {

// Adds `completion` to `app`; the script it prints covers every subcommand added to `app` before
// the command line is parsed.
void add_completion_command(CLI::App& app, int& exit_code);

}  // namespace hmc::cli
