// `hmc`: the command line over libhmc. Parses arguments, runs one subcommand, and turns every
// outcome into an exit code in this one place (docs/cli.md lists them).
#include <iostream>

#include <CLI/CLI.hpp>

#include "board_commands.h"
#include "completion_command.h"
#include "config_command.h"
#include "connection.h"
#include "exit_codes.h"
#include "flash_command.h"
#include "frame_command.h"
#include "grbl_command.h"
#include "jog_command.h"
#include "motion_commands.h"
#include "ports_command.h"
#include "sim_command.h"
#include "zero_command.h"

#ifndef HMC_VERSION
#error "HMC_VERSION must be defined by the build"
#endif

int main(int argc, char** argv) {
  CLI::App app{"hmc: tools for the Hybrid Motor Controller board (steppers, servos, LED strips)", "hmc"};
  app.set_version_flag("--version", std::string("hmc ") + HMC_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Examples:\n"
      "  hmc frame encode STM 1 1 128 1000 500     # -> STX#6#STM#1#1#128#1000#500#94#ETX\n"
      "  hmc frame encode '[#SVM#1#135]'           # spec's command-set notation\n"
      "  hmc frame decode 'STX#6#STM#3#1#1#11#1000#238#ETX'\n"
      "  hmc frame check frames.txt                # one verdict per line\n"
      "  hmc --port sim:// move 1 3200 --accel 8000 --wait   # the simulated board, no hardware\n"
      "  hmc --port /dev/ttyUSB0 status            # motors, switches, servos, LED strips\n"
      "  hmc home all && hmc led 1 '#ff800000' && hmc servo 1 135\n"
      "  hmc monitor                               # replies and events as they come\n"
      "  hmc flash --port /dev/ttyACM0 --dry-run   # what flashing the built firmware would run\n"
      "\n"
      "Exit codes: 0 ok, 1 refused, 2 usage, 3 port or file, 4 no reply, 5 motion ended early,\n"
      "130 interrupted (docs/cli.md).");

  int exit_code = hmc::cli::kExitOk;
  hmc::cli::GlobalOptions global;
  hmc::cli::add_global_options(app, global);
  app.fallthrough();  // global options may follow the subcommand: `hmc status --port sim://`
  hmc::cli::add_frame_command(app, exit_code);
  hmc::cli::add_board_commands(app, global, exit_code);
  hmc::cli::add_motion_commands(app, global, exit_code);
  hmc::cli::add_ports_command(app, exit_code);
  hmc::cli::add_sim_command(app, exit_code);
  hmc::cli::add_flash_command(app, exit_code);
  hmc::cli::add_completion_command(app, exit_code);
  hmc::cli::add_config_command(app, global, exit_code);
  hmc::cli::add_zero_command(app, global, exit_code);
  hmc::cli::add_grbl_command(app, global, exit_code);
  hmc::cli::add_jog_command(app, global, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? hmc::cli::kExitOk : hmc::cli::kExitUsage;
  }
  return exit_code;
}
