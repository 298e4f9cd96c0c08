// The exit codes of `hmc`, one place for all (documented in docs/cli.md).
#pragma once

namespace hmc::cli {

enum ExitCode : int {
  kExitOk = 0,        // done; every frame valid
  kExitInvalid = 1,   // a frame or command was refused (by the codec or the board)
  kExitUsage = 2,     // the command line itself is wrong
  kExitIo = 3,        // a file, port or connection could not be used
};

}  // namespace hmc::cli
