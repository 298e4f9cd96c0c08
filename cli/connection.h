// What every board command shares: the global options (--port, --baud, --timeout, --json, -v,
// --firmware, --profile), finding the port, opening the session, Ctrl-C, and turning a session's errors into
// messages and exit codes (docs/cli.md).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "hmc/session.h"

namespace hmc::cli {

struct GlobalOptions {
  std::string port;        // --port / HMC_PORT; empty: the one likely board
  uint32_t baud = 115200;  // --baud
  int timeout_ms = 1000;   // --timeout: longest wait for one reply
  bool json = false;       // --json
  int verbose = 0;         // -v: every line sent and received, on standard error
  std::string firmware = "auto";  // --firmware auto|v2|seed
  int watchdog_ms = 500;   // --watchdog: the link watchdog long-lived commands arm; 0 none
  std::string profile;     // --profile (HMC_PROFILE read where the profile is chosen: profile_choice.h)
  // The options as parsed: a value the command line (or HMC_PORT) did not give comes from the profile.
  const CLI::Option* port_option = nullptr;
  const CLI::Option* baud_option = nullptr;
  const CLI::Option* firmware_option = nullptr;
};

// Adds the global options to the top-level app (they may also follow a subcommand).
void add_global_options(CLI::App& app, GlobalOptions& options);

using LineHandler = std::function<void(std::string_view line, const Result<BoardFrame, Diagnostic>& frame)>;

// Opens the port and the session; says on standard error which board is driven (unless --json).
// `on_line` sees every line the board sends. On failure prints the error and returns nullptr
// with `exit_code` set.
std::unique_ptr<Session> connect(const GlobalOptions& options, int& exit_code, LineHandler on_line = nullptr);

// For commands that keep the board busy (run, stream, move --wait, home, monitor): arms the
// board's link watchdog (--watchdog), so the motors brake if this process dies without a word;
// the session keeps the link alive and disarms it when it ends. A board without one (seed
// firmware, protocol 2) gets a note on standard error and the command goes on.
SessionResult<Done> watch_link(Session& session, const GlobalOptions& options);

// A number above 0, refused in words ("must be above 0, not '-1'"), not with CLI11's range that
// writes out the largest double.
CLI::Validator positive_number();

// Raised by SIGINT, SIGTERM and SIGHUP; a session's waits poll it.
bool interrupt_requested();

// Prints a session error (as {"error": {...}} with --json) and returns its exit code.
int report_error(const GlobalOptions& options, const SessionError& error);

// The JSON form of the board model (status, and the end of moves).
nlohmann::json model_to_json(const Session& session);
nlohmann::json motor_to_json(const MotorStatus& motor, const std::optional<MotionEnd>& last_end);

// "a: 3200 steps of 1/16 (200 full steps)" for people.
std::string position_words(const MotorStatus& motor);
// The seed firmware reports no positions: "400 steps of 1/16 from where this hmc found it".
std::string seed_position_words(const MotorStatus& motor);

}  // namespace hmc::cli
