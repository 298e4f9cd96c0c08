// hmc-sim's command line (docs/sim.md, "Options"): what the options mean, mapped onto a
// SimConfig, and the parsers of their values.
#pragma once

#include <stdint.h>

#include <optional>
#include <string>
#include <string_view>

#include "sim_board.h"
#include "sim_result.h"

namespace hmc::sim {

enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 2,  // a bad option or script line
  kExitIo = 3,     // a file, port or pseudo-terminal could not be used
};

struct HostPort {
  std::string host;
  uint16_t port = 0;  // 0: any free port
};

enum class LinkKind : uint8_t { kStdio, kTcp, kPty };

struct SimOptions {
  SimConfig config;
  LinkKind link = LinkKind::kStdio;
  HostPort tcp;                     // kTcp
  std::optional<HostPort> control;  // --control
  bool fast = false;
  std::string trace;   // empty: none; "-": standard error
  std::string script;  // empty: none
  bool exit_when_idle = false;
  bool quiet = false;
};

// The command line, or the exit code when it is wrong or asked for help or the version (the
// message is already printed then).
struct ParsedArgs {
  std::optional<SimOptions> options;
  int exit_code = kExitOk;
};
ParsedArgs parse_args(int argc, const char* const* argv);

// Option values. HOST:PORT (an IPv6 host in brackets: [::1]:4000).
Result<HostPort> parse_host_port(std::string_view text);
// --accel M:A: motor 1-3, steps/s².
struct AccelOption {
  uint8_t motor = 0;
  uint32_t steps_per_s2 = 0;
};
Result<AccelOption> parse_accel(std::string_view text);
// --axis M:LOW:HIGH:START: motor 1-2, positions in 1/256 step, LOW below HIGH.
struct AxisOption {
  uint8_t motor = 0;
  AxisConfig axis;
};
Result<AxisOption> parse_axis(std::string_view text);

}  // namespace hmc::sim
