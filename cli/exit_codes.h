// The exit codes of `hmc`, one place for all (documented in docs/cli.md).
#pragma once

namespace hmc::cli {

enum ExitCode : int {
  kExitOk = 0,           // done; every frame valid
  kExitInvalid = 1,      // a frame or command was refused (by the codec, the host's checks or the board)
  kExitUsage = 2,        // the command line itself is wrong
  kExitIo = 3,           // a file, port or connection could not be used, or was lost
  kExitNoReply = 4,      // the board stopped answering, or a motion did not end in time
  kExitIncomplete = 5,   // a motion ended early: a limit switch, the emergency switch, a stop
  kExitInterrupted = 130,  // Ctrl-C (128 + SIGINT); every motor was sent a stop
};

}  // namespace hmc::cli
