// The global options, the port, the session, Ctrl-C, and errors as messages and exit codes.
#include "connection.h"

#include <signal.h>

#include <cstdlib>
#include <iostream>

#include "axis_units.h"
#include "exit_codes.h"
#include "profile_choice.h"
#include "hmc/command_json.h"
#include "hmc/port_list.h"
#include "hmc/transport.h"

namespace hmc::cli {
namespace {

volatile sig_atomic_t g_interrupted = 0;

void on_interrupt(int) { g_interrupted = 1; }

// Ctrl-C raises a flag instead of ending the program: the session sees it in its waits and
// stops the motors. No SA_RESTART, so a blocking read returns at once.
void catch_interrupts() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGHUP, &action, nullptr);  // a closed terminal or a dropped SSH session
  signal(SIGPIPE, SIG_IGN);  // a closed connection is an error from write, not a signal
}

const char* kind_name(SessionError::Kind kind) {
  switch (kind) {
    case SessionError::Kind::kInvalid: return "invalid";
    case SessionError::Kind::kRefused: return "refused";
    case SessionError::Kind::kNak: return "refused_by_board";
    case SessionError::Kind::kNoReply: return "no_reply";
    case SessionError::Kind::kLink: return "link";
    case SessionError::Kind::kInterrupted: return "interrupted";
    case SessionError::Kind::kTooOld: return "firmware_too_old";
    case SessionError::Kind::kEnded: return "ended_early";
  }
  return "link";
}

int exit_code_of(SessionError::Kind kind) {
  switch (kind) {
    case SessionError::Kind::kInvalid:
    case SessionError::Kind::kRefused:
    case SessionError::Kind::kNak:
    case SessionError::Kind::kTooOld: return kExitInvalid;
    case SessionError::Kind::kNoReply: return kExitNoReply;
    case SessionError::Kind::kLink: return kExitIo;
    case SessionError::Kind::kInterrupted: return kExitInterrupted;
    case SessionError::Kind::kEnded: return kExitIncomplete;
  }
  return kExitIo;
}

// The port to use when none is named: the one likely board, or an error that says what to do.
Result<std::string> default_port(bool quiet) {
  Result<std::vector<PortInfo>> ports = list_ports();
  if (!ports) return ports.error();
  if (std::optional<std::string> board = find_board_port(*ports)) {
    if (!quiet) std::cerr << "hmc: no --port given; using " << *board << ", the one FT232R bridge found\n";
    return *board;
  }
  size_t likely = 0;
  for (const PortInfo& p : *ports) likely += p.likely_board ? 1 : 0;
  const std::string found = likely > 1 ? std::to_string(likely) + " FT232R bridges found, which is ambiguous"
                                       : "no FT232R bridge among the " + std::to_string(ports->size()) + " serial ports";
  return Error{"no --port given and " + found +
               ". Name the port with --port (or HMC_PORT); `hmc ports` lists them, and --port sim:// drives the "
               "simulated board"};
}

}  // namespace

void add_global_options(CLI::App& app, GlobalOptions& o) {
  o.port_option = app.add_option("-p,--port", o.port,
                 "the board: /dev/ttyUSB0, tcp://HOST:PORT, a pseudo-terminal, sim:// for the simulated board, or emu:// for "
                 "the firmware image on hmc-emu "
                 "(default: the one FT232R bridge found)")
      ->envname("HMC_PORT");
  o.baud_option = app.add_option("--baud", o.baud, "serial baud rate (default 115200)")->check(CLI::Range(300u, 4000000u));
  app.add_option("--timeout", o.timeout_ms, "ms to wait for each reply (default 1000)")->check(CLI::Range(10, 600000));
  app.add_flag("--json", o.json, "machine-readable output (docs/cli.md)");
  app.add_flag("-v,--verbose", o.verbose, "show every line sent (>) and received (<) on standard error");
  app.add_option("--watchdog", o.watchdog_ms,
                 "ms without a line after which the board brakes every motor, armed by run, stream, move --wait, "
                 "home and monitor (default 500; 0: none)")
      ->check(CLI::Range(0, static_cast<int>(proto::kWatchdogMaxMs)));
  o.firmware_option = app.add_option("--firmware", o.firmware, "auto (ask VER), v2, or seed (a board that answers nothing)")
      ->check(CLI::IsMember({"auto", "v2", "seed"}));
  app.add_option("--profile", o.profile,
                 "the machine profile: axes by name, units, port (default: HMC_PROFILE, else "
                 "$XDG_CONFIG_HOME/hmc/config.toml when it exists; docs/config.md)");
}

bool interrupt_requested() { return g_interrupted != 0; }

CLI::Validator positive_number() {
  return CLI::Validator(
      [](const std::string& text) {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool number = !text.empty() && end != nullptr && *end == '\0';
        return number && value > 0 ? std::string() : "must be a number above 0, not '" + text + "'";
      },
      "NUMBER > 0");
}

SessionResult<Done> watch_link(Session& s, const GlobalOptions& o) {
  // sim://'s board runs only inside hmc: when hmc dies its time stops too, so nothing runs on
  // unwatched.
  if (o.watchdog_ms == 0 || s.simulated()) return Done{};
  if (SessionResult<Done> able = s.require(proto::Feature::kLinkWatchdog); !able) {
    if (!o.json) {
      std::cerr << "note: no link watchdog: " << able.error().message
                << "; if hmc dies, running motors keep running\n";
    }
    return Done{};
  }
  return s.arm_watchdog(Millis{o.watchdog_ms});
}

std::unique_ptr<Session> connect(const GlobalOptions& given, int& exit_code, LineHandler on_line) {
  Result<GlobalOptions, int> profiled = with_profile_link(given);
  if (!profiled) {
    exit_code = profiled.error();
    return nullptr;
  }
  const GlobalOptions& o = *profiled;
  std::string name = o.port;
  if (name.empty()) {
    Result<std::string> found = default_port(o.json);
    if (!found) {
      exit_code = report_error(o, SessionError{SessionError::Kind::kLink, found.error().message, proto::Reason::kOk});
      return nullptr;
    }
    name = *found;
  }
  PortOptions port_options;
  port_options.baud = o.baud;
  Result<std::unique_ptr<Transport>> port = open_port(name, port_options);
  if (!port) {
    exit_code = report_error(o, SessionError{SessionError::Kind::kLink, port.error().message, proto::Reason::kOk});
    return nullptr;
  }
  catch_interrupts();
  SessionOptions options;
  options.firmware = o.firmware == "v2"     ? FirmwareChoice::kV2
                     : o.firmware == "seed" ? FirmwareChoice::kSeed
                                            : FirmwareChoice::kDetect;
  options.reply_timeout = Millis{o.timeout_ms};
  options.baud = o.baud;
  options.interrupted = interrupt_requested;
  if (o.verbose > 0) options.on_send = [](std::string_view line) { std::cerr << "> " << line << '\n'; };
  options.on_line = [verbose = o.verbose > 0, on_line](std::string_view line, const Result<BoardFrame, Diagnostic>& frame) {
    if (verbose) std::cerr << "< " << line << '\n';
    if (on_line) on_line(line, frame);
  };
  SessionResult<std::unique_ptr<Session>> session = Session::open(std::move(*port), options);
  if (!session) {
    exit_code = report_error(o, session.error());
    return nullptr;
  }
  if (!o.json) std::cerr << "board: " << session.value()->description() << '\n';
  // The profile's soft limits, for the board to enforce too (on axes whose position means something).
  if (const Result<const Profile*, int> profile = use_profile(o); profile && *profile != nullptr) {
    for (const Axis& axis : (*profile)->axes) {
      if (Status sent = send_soft_limits(*session.value(), axis); !sent) {
        exit_code = report_error(o, SessionError{SessionError::Kind::kNak, sent.error().message, proto::Reason::kOk});
        return nullptr;
      }
    }
  }
  return std::move(session.value());
}

int report_error(const GlobalOptions& o, const SessionError& error) {
  if (o.json) {
    nlohmann::json e{{"kind", kind_name(error.kind)}, {"message", error.message}};
    e["reason"] = error.reason == proto::Reason::kOk ? nlohmann::json(nullptr)
                                                     : nlohmann::json(proto::reason_spec(error.reason).name);
    std::cout << nlohmann::json{{"error", e}} << '\n';
  } else {
    std::cerr << "error: " << error.message << '\n';
  }
  return exit_code_of(error.kind);
}

std::string position_words(const MotorStatus& m) {
  return "at " + steps_text(m.position * m.microstep) + " steps of 1/" + std::to_string(m.microstep) + " (" +
         steps_text(m.position) + " full steps)";
}

std::string seed_position_words(const MotorStatus& m) {
  return steps_text(m.position * m.microstep) + " steps of 1/" + std::to_string(m.microstep) +
         " from where this hmc found it";
}

nlohmann::json motor_to_json(const MotorStatus& m, const std::optional<MotionEnd>& last_end) {
  // Steps of the microstep: a whole number, unless the position falls between two of them.
  const int64_t units = static_cast<int64_t>(m.position) * m.microstep;
  const nlohmann::json steps = units % 256 == 0 ? nlohmann::json(units / 256) : nlohmann::json(static_cast<double>(units) / 256.0);
  return {{"motor", m.motor},
          {"state", motor_state_name(m.state)},
          {"position", m.position},
          {"steps", steps},
          {"target", m.target},
          {"microstep", m.microstep},
          {"rate", m.rate},
          {"homed", m.homed},
          {"endless", m.endless && m.state != MotorState::kIdle},  // a resting motor runs toward nothing
          {"switches", proto::motor_has_switches(m.motor)
                           ? nlohmann::json{{"reverse", (m.switches & 1u) != 0}, {"forward", (m.switches & 2u) != 0}}
                           : nlohmann::json(nullptr)},
          {"last_end", last_end ? nlohmann::json(motion_end_name(*last_end)) : nlohmann::json(nullptr)}};
}

nlohmann::json model_to_json(const Session& s) {
  const BoardModel& model = s.model();
  nlohmann::json j;
  j["board"] = s.description();
  j["firmware"] = s.firmware() == Firmware::kV2 ? "v2" : "seed";
  j["version"] = s.version() ? board_frame_to_json(BoardFrame{*s.version()}) : nlohmann::json(nullptr);
  const StepBudgets budgets = s.step_budgets_in_force();
  j["step_budgets"] = {{"constant", budgets.constant},
                       {"ramping", budgets.ramping},
                       {"reported", s.supports(proto::Feature::kStepBudgets)}};
  j["reported"] = model.reported;
  j["emergency"] = model.board.emergency;
  j["watchdog"] = model.watchdog ? board_frame_to_json(BoardFrame{*model.watchdog}) : nlohmann::json(nullptr);
  j["motors"] = nlohmann::json::array();
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) j["motors"].push_back(motor_to_json(model.motor(m), model.last_end[m - 1]));
  j["servos"] = {{{"servo", 1}, {"pulse_us", model.board.servo1_us}}, {{"servo", 2}, {"pulse_us", model.board.servo2_us}}};
  j["strips"] = nlohmann::json::array();
  for (const StripStatus& l : model.strips) {
    j["strips"].push_back({{"strip", l.strip}, {"r", l.r}, {"g", l.g}, {"b", l.b}, {"w", l.w}});
  }
  if (model.last_reset) {
    nlohmann::json reset = board_frame_to_json(BoardFrame{ResetStatus{*model.last_reset}});
    reset.erase("name");
    reset["text"] = reset_text(*model.last_reset);
    j["last_reset"] = reset;
  } else {
    j["last_reset"] = nullptr;  // a board older than protocol 4, or the seed firmware
  }
  return j;
}

}  // namespace hmc::cli
