// The commands that talk to a board: send, move, home, stop, servo, led, status, monitor. Each
// parses its arguments into commands, hands them to the session, and reports in words or JSON.
#include "board_commands.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "axis_units.h"
#include "exit_codes.h"
#include "hmc/codec.h"
#include "hmc/command_json.h"
#include "profile_choice.h"
#include "report.h"

namespace hmc::cli {
namespace {

constexpr uint32_t kDefaultDelayUs = kDefaultMoveDelayUs;
constexpr uint32_t kFullStepsPerRev = kDefaultStepsPerRev;

// One command's run: connect, act, and set the exit code; `act` returns an exit code.
template <typename Act>
void run_on_board(const GlobalOptions& g, int& exit_code, Act act) {
  std::unique_ptr<Session> session = connect(g, exit_code);
  if (session) exit_code = act(*session);
}

// The profile in use (connect() has loaded it, or failed): nullptr when there is none.
const Profile* profile_in_use(const GlobalOptions& g) {
  Result<const Profile*, int> profile = use_profile(g);
  return profile ? *profile : nullptr;
}

int usage_error(const GlobalOptions& g, const std::string& message) {
  report_error(g, SessionError{SessionError::Kind::kInvalid, message, proto::Reason::kOk});
  return kExitUsage;
}

// The command line's values against the protocol's ranges, before the port opens: a value out
// of range there is a usage error (exit 2) and nothing is sent. False when it was reported.
bool command_line_valid(const GlobalOptions& g, const Command& command, int& exit_code) {
  if (Result<Command, Diagnostic> valid = validate(command); !valid) {
    exit_code = usage_error(g, valid.error().message);
    return false;
  }
  return true;
}

enum class Motion : uint8_t { kMove, kHome, kStop };

// What the seed firmware's silence leaves known after a motion was sent and its time waited out:
// positions count from where this hmc found the motor, and a home's or a stop's outcome is unknown.
std::string seed_result_words(Motion motion, const MotorStatus& motor) {
  constexpr const char* kSent = "sent; the original firmware confirms nothing";
  switch (motion) {
    case Motion::kMove:
      return std::string(kSent) + " (if it obeyed, it is " + seed_position_words(motor) + ")";
    case Motion::kHome:
      return std::string("home ") + kSent + " (if it obeyed, it found its switch within the steps given)";
    case Motion::kStop:
      return std::string("stop ") + kSent + ", and where the motor stopped is unknown: it reports no positions";
  }
  return kSent;
}

// What a servo or LED command sent to the seed firmware leaves unknown.
constexpr const char* kSeedIgnores =
    ": sent; the original firmware confirms nothing, and it ignores servo and LED commands while a stepper runs "
    "(which this hmc cannot see of motors an earlier command started)";

// Waits for the motors, then reports each one's end; the exit code says whether all completed.
int wait_and_report(const GlobalOptions& g, Session& s, const std::vector<uint32_t>& motors, Motion motion) {
  const bool homing = motion == Motion::kHome;
  if (SessionResult<Done> waited = s.wait_until_idle(motors); !waited) {
    const int code = report_error(g, waited.error());
    if (waited.error().kind == SessionError::Kind::kInterrupted && !g.json) {
      for (const uint32_t m : motors) std::cerr << "motor " << m << " stopped " << position_words(s.model().motor(m)) << '\n';
    }
    return code;
  }
  int code = kExitOk;
  nlohmann::json out = nlohmann::json::array();
  for (const uint32_t m : motors) {
    const MotorStatus& motor = s.model().motor(m);
    const std::optional<MotionEnd>& end = s.model().last_end[m - 1];
    const bool early = homing ? (s.firmware() == Firmware::kV2 && !motor.homed)
                              : (motion == Motion::kMove && end && *end != MotionEnd::kCompleted);
    if (early) code = kExitIncomplete;
    if (g.json) {
      out.push_back(motor_to_json(motor, end));
      continue;
    }
    // Homing halted by the emergency switch ends without its switch too: name the real cause.
    std::string how = homing ? (motor.homed ? "homed" : "not homed: " + not_homed_cause(s.model())) : "done";
    if (motion == Motion::kMove && end && *end != MotionEnd::kCompleted) {
      how = std::string("ended early: ") + motion_end_name(*end);
    }
    if (motion == Motion::kStop) how = "stopped";
    if (s.firmware() == Firmware::kSeed) {
      // Nothing came back: say what was sent, and only what follows from it if the board obeyed.
      std::cout << "motor " << m << ": " << seed_result_words(motion, motor) << '\n';
      continue;
    }
    std::cout << "motor " << m << ": " << how << ", " << position_words(motor) << '\n';
  }
  if (g.json) std::cout << nlohmann::json{{"motors", out}} << '\n';
  return code;
}

// --- send ---------------------------------------------------------------------------------

// The lines of `--raw TEXT` as the board splits them (LF, CR or CRLF); a last line end ends the
// last line. '' is one blank line.
std::vector<std::string> raw_lines(const std::string& text) {
  std::vector<std::string> lines{""};
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\r' && text[i] != '\n') {
      lines.back() += text[i];
      continue;
    }
    if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
    if (i + 1 < text.size()) lines.emplace_back();
  }
  return lines;
}

void show_reply(const GlobalOptions& g, const Session& s, const BoardFrame& reply) {
  if (g.json) {
    std::cout << nlohmann::json{{"reply", s.firmware() == Firmware::kSeed ? nlohmann::json(nullptr)
                                                                           : board_frame_to_json(reply)}}
              << '\n';
  } else if (s.firmware() == Firmware::kSeed) {
    std::cout << "sent (the seed firmware does not reply)\n";
  } else {
    print_board_frame(std::cout, reply);
  }
}

void add_send(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string first;                // kept whole: a list option would lose `[...]` around it
    std::vector<std::string> values;  // after a command name
    bool raw = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("send", "send one command: a frame, [#NAME#v1#...] or NAME v1 ... and show the reply");
  cmd->add_option("command", o->first, "STX#...#ETX, '[#SVM#1#135]', or a name: SVM 1 135")->required();
  cmd->add_option("values", o->values, "the values after a command name");
  cmd->add_flag("--raw", o->raw, "send the first argument's bytes unchanged, unchecked (to see the board refuse)");
  cmd->callback([&g, &exit_code, o] {
    if (o->raw && !o->values.empty()) {
      exit_code = usage_error(g, "--raw takes the line as one argument (quote it)");
      return;
    }
    // A command (not --raw) is read and checked before the port opens: a mistake sends nothing.
    std::optional<Command> command;
    if (!o->raw) {
      std::vector<std::string> words{o->first};
      words.insert(words.end(), o->values.begin(), o->values.end());
      Result<Command, Diagnostic> parsed = o->values.empty() ? command_from_text(o->first) : command_from_words(words);
      if (parsed) parsed = validate(*parsed);
      if (!parsed) {
        if (g.json) {
          report_error(g, SessionError{SessionError::Kind::kInvalid, parsed.error().message, parsed.error().reason});
        } else {
          print_refusal(std::cerr, o->values.empty() ? o->first : "", parsed.error());
        }
        exit_code = kExitInvalid;
        return;
      }
      command = *parsed;
    }
    run_on_board(g, exit_code, [&](Session& s) {
      if (command) {
        SessionResult<BoardFrame> reply = s.execute(*command);
        if (!reply) return report_error(g, reply.error());
        show_reply(g, s, *reply);
        return static_cast<int>(kExitOk);
      }
      // Each line is answered on its own (a blank one not at all): one reply shown per line.
      for (const std::string& line : raw_lines(o->first)) {
        if (is_blank(line) && s.firmware() == Firmware::kV2) {
          if (SessionResult<BoardFrame> sent = s.send_line(line); !sent) return report_error(g, sent.error());
          if (g.json) {
            std::cout << nlohmann::json{{"reply", nullptr}} << '\n';
          } else {
            std::cout << "sent a blank line: the board answers nothing to it (it only feeds the link watchdog)\n";
          }
          continue;
        }
        SessionResult<BoardFrame> answered = s.send_line(line);
        if (!answered) return report_error(g, answered.error());
        show_reply(g, s, *answered);
      }
      return static_cast<int>(kExitOk);
    });
  });
}

// --- stream -------------------------------------------------------------------------------

void add_stream(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string path;
    bool one_at_a_time = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "stream", "send a file of commands (one per line: frame, [#...] or words) as fast as the link allows");
  cmd->add_option("file", o->path, "the file, or - for standard input")->required();
  cmd->add_flag("--one-at-a-time", o->one_at_a_time, "wait for each reply before the next line (for comparison)");
  cmd->callback([&g, &exit_code, o] {
    // Every line is read and checked before the port is opened: a file with a mistake sends nothing.
    std::ifstream file;
    if (o->path != "-") {
      file.open(o->path, std::ios::binary);
      if (!file) {
        exit_code = report_error(g, SessionError{SessionError::Kind::kLink, "cannot read " + o->path, proto::Reason::kOk});
        return;
      }
    }
    std::istream& in = o->path == "-" ? std::cin : file;
    std::vector<Command> commands;
    std::vector<size_t> line_numbers;
    std::string text;
    for (size_t number = 1; std::getline(in, text); ++number) {
      if (!text.empty() && text.back() == '\r') text.pop_back();
      // A comment: a line whose first non-blank byte is '#' (no frame or command begins so).
      const size_t first = text.find_first_not_of(" \t");
      if (first == std::string::npos || text[first] == '#') continue;
      Result<Command, Diagnostic> command = command_from_text(text);
      if (!command) {
        std::cerr << o->path << ":" << number << ": ";
        print_refusal(std::cerr, text, command.error());
        exit_code = kExitInvalid;
        return;
      }
      commands.push_back(*command);
      line_numbers.push_back(number);
    }
    run_on_board(g, exit_code, [&](Session& s) {
      if (SessionResult<Done> watched = watch_link(s, g); !watched) return report_error(g, watched.error());
      const Clock::time_point start = Clock::now();
      SessionResult<Session::StreamReport> report = s.stream(commands, !o->one_at_a_time);
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      if (!report) return report_error(g, report.error());
      size_t bytes = 0;
      for (size_t i = 0; i < report->sent; ++i) bytes += encode(commands[i]).value().size() + 1;
      const double capacity = g.baud / 10.0;
      const double share = seconds > 0 ? static_cast<double>(bytes) / seconds / capacity : 0.0;
      if (g.json) {
        nlohmann::json j{{"sent", report->sent}, {"accepted", report->accepted}, {"bytes", bytes},
                         {"seconds", seconds}, {"link_share", share}};
        if (report->refused) {
          j["refused"] = {{"index", *report->refused + 1}, {"line", line_numbers[*report->refused]}, {"why", report->why}};
          j["refused_after"] = nlohmann::json::array();
          for (size_t i = 0; i < report->refused_after.size(); ++i) {
            const size_t k = report->refused_after[i];
            j["refused_after"].push_back({{"index", k + 1}, {"line", line_numbers[k]}, {"why", report->why_after[i]}});
          }
          j["stopped"] = report->stopped;
        }
        std::cout << j << '\n';
      } else {
        std::cout << "streamed " << report->sent << " of " << commands.size() << " lines, " << bytes << " bytes in "
                  << std::fixed << std::setprecision(3) << seconds << " s: " << std::setprecision(1) << share * 100
                  << " % of the line's " << static_cast<int>(capacity) << " bytes/s"
                  << (o->one_at_a_time ? " (one at a time)" : "") << '\n';
      }
      if (!report->refused) return static_cast<int>(kExitOk);
      if (!g.json) {
        const size_t k = *report->refused;
        const size_t after = report->sent - k - 1;
        std::cerr << "error: " << o->path << ":" << line_numbers[k] << " (command " << k + 1 << ") was refused: " << report->why
                  << "\n  the " << k << " commands before it were carried out; " << after
                  << " more were already on their way and " << (after - report->refused_after.size())
                  << " of them were carried out; nothing after those was sent\n";
        for (size_t i = 0; i < report->refused_after.size(); ++i) {
          const size_t r = report->refused_after[i];
          std::cerr << "  " << o->path << ":" << line_numbers[r] << " (command " << r + 1
                    << "), on its way, was refused too: " << report->why_after[i] << '\n';
        }
        for (const uint32_t m : report->stopped) {
          std::cerr << "  motor " << m << ", started by the stream, was stopped: "
                    << position_words(s.model().motor(m)) << '\n';
        }
      }
      return static_cast<int>(kExitInvalid);
    });
  });
}

// --- move ---------------------------------------------------------------------------------

struct MoveOptions {
  std::string axis;   // a motor number or a profile axis
  uint32_t motor = 1;
  std::optional<double> steps;
  std::optional<double> degrees;
  std::optional<double> revolutions;
  std::optional<uint32_t> microstep;
  std::optional<uint32_t> delay_us;
  std::optional<double> rate;
  std::optional<std::string> accel;   // steps/s^2, or a quantity for the axis
  std::optional<std::string> to, by, speed;  // quantities for the axis
  uint32_t steps_per_rev = kFullStepsPerRev;
  bool run = false;
  bool reverse = false;
  bool wait = false;
};

// The STM frame a move's options mean, or why they are wrong.
Result<StepperMove> move_command(const MoveOptions& o, uint32_t current_microstep) {
  const int given = (o.steps ? 1 : 0) + (o.degrees ? 1 : 0) + (o.revolutions ? 1 : 0) + (o.run ? 1 : 0);
  if (given != 1) return Error{"give the distance once: STEPS, --deg, --rev, or --run (until stopped)"};
  if (o.delay_us && o.rate) return Error{"give --delay or --rate, not both"};
  StepperMove move;
  move.motor = o.motor;
  move.microstep = o.microstep.value_or(current_microstep);
  double steps = 0;
  if (o.steps) steps = *o.steps;
  if (o.degrees) steps = *o.degrees / 360.0 * o.steps_per_rev * move.microstep;
  if (o.revolutions) steps = *o.revolutions * o.steps_per_rev * move.microstep;
  if (!o.run && std::llround(steps) == 0) return Error{"the move is 0 steps (at 1/" + std::to_string(move.microstep) + " step)"};
  if (std::fabs(steps) > 2147483647.0) return Error{"the move is more than 2147483647 steps"};
  const bool backward = (steps < 0) != o.reverse;
  move.dir = backward ? proto::kActionReverse : proto::kActionForward;
  move.steps = static_cast<uint32_t>(std::llabs(std::llround(steps)));
  move.delay_us = o.delay_us.value_or(kDefaultDelayUs);
  if (o.rate) {
    if (*o.rate <= 0) return Error{"--rate must be above 0 steps/s"};
    move.delay_us = static_cast<uint32_t>(std::llround(1e6 / *o.rate));
  }
  return move;
}

void add_move(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  auto o = std::make_shared<MoveOptions>();
  CLI::App* cmd = app.add_subcommand(
      "move", "move a stepper: STEPS (negative: reverse), --deg or --rev, --run, or in the axis's units --to/--by");
  cmd->add_option("motor", o->axis, "stepper 1-3, or an axis of the profile by name")->required();
  cmd->add_option("--to", o->to, "go to this position: 250mm, 90deg, 2rev, 3200steps (docs/config.md)");
  cmd->add_option("--by", o->by, "move this far from where the axis is: -90deg, 12.5mm");
  cmd->add_option("--speed", o->speed, "with --to/--by: 20mm/s, 45deg/s (default: the profile's speed)");
  cmd->add_option("steps", o->steps, "steps at the microstep (negative: reverse)");
  cmd->add_option("--deg", o->degrees, "degrees instead of steps (--steps-per-rev full steps per turn)");
  cmd->add_option("--rev", o->revolutions, "revolutions instead of steps");
  cmd->add_flag("--run", o->run, "run until stopped (hmc stop)");
  cmd->add_flag("--reverse", o->reverse, "move in reverse");
  cmd->add_option("--microstep", o->microstep, "1, 2, 4 ... 256 (default: the motor's current one)");
  cmd->add_option("--delay", o->delay_us, "us per step (default 500)");
  cmd->add_option("--rate", o->rate, "steps per second instead of --delay");
  cmd->add_option("--accel", o->accel,
                  "steps/s^2 to ramp up and down, or 100mm/s2 (0: constant rate; v2 firmware; default with --to/--by: "
                  "the profile's)");
  cmd->add_option("--steps-per-rev", o->steps_per_rev, "full steps per turn for --deg and --rev (default 200)")
      ->check(CLI::Range(1u, 100000u));
  cmd->add_flag("--wait", o->wait, "wait until the motor stops and print where it is");
  cmd->callback([&g, &exit_code, o] {
    // An axis no one has is a mistake on the command line: found before the port is opened.
    Result<const Profile*, int> profile = use_profile(g);
    if (!profile) {
      exit_code = profile.error();
      return;
    }
    Result<Axis> known = resolve_axis(o->axis, *profile, BoardModel{}, o->steps_per_rev);
    if (!known) {
      exit_code = usage_error(g, known.error().message);
      return;
    }
    // The rest of the command line too, as far as it does not depend on where the motor is.
    const auto mistake = [&]() -> std::optional<std::string> {
      if (o->to || o->by) {
        if (o->steps || o->degrees || o->revolutions || o->run || o->delay_us || o->rate || o->microstep || o->reverse) {
          return "--to and --by take the axis's microstep and --speed: no STEPS, --deg, --rev, --run, --delay, --rate, "
                 "--microstep or --reverse with them";
        }
        Result<UnitMove> planned =
            unit_move(*known, BoardModel{}.motor(known->motor), UnitMoveRequest{o->to, o->by, o->speed, o->accel});
        if (!planned) return planned.error().message;
        return std::nullopt;
      }
      if (o->speed) return "--speed goes with --to or --by; give STEPS with --delay or --rate";
      MoveOptions given = *o;
      given.motor = known->motor;
      Result<StepperMove> move = move_command(given, o->microstep.value_or(known->microstep));
      if (!move) return move.error().message;
      if (Result<Command, Diagnostic> valid = validate(*move); !valid) return valid.error().message;
      if (o->accel) {
        std::vector<std::string> notes;
        Result<uint32_t> steps = accel_steps(*known, *o->accel, notes);
        if (!steps) return steps.error().message;
        if (Result<Command, Diagnostic> valid = validate(SetSetting{known->motor, proto::kSettingAccel, *steps}); !valid) {
          return "--accel: " + valid.error().message;
        }
      }
      return std::nullopt;
    }();
    if (mistake) {
      exit_code = usage_error(g, *mistake);
      return;
    }
    run_on_board(g, exit_code, [&](Session& s) {
      Result<Axis> axis = resolve_axis(o->axis, profile_in_use(g), s.model(), o->steps_per_rev);
      if (!axis) return usage_error(g, axis.error().message);
      o->motor = axis->motor;
      std::vector<std::string> notes;
      std::optional<uint32_t> accel;
      Result<StepperMove> move = Error{""};
      if (o->to || o->by) {
        Result<UnitMove> planned = unit_move(*axis, s.model().motor(axis->motor), UnitMoveRequest{o->to, o->by, o->speed, o->accel});
        if (!planned) return usage_error(g, planned.error().message);
        if (std::optional<std::string> refused = beyond_soft_limits(*axis, s.model().motor(axis->motor), planned->target)) {
          return report_error(g, SessionError{SessionError::Kind::kRefused, *refused, proto::Reason::kOk});
        }
        notes = planned->notes;
        accel = planned->accel;
        if (!planned->move) {
          if (!g.json) std::cout << axis_position_words(*axis, s.model().motor(axis->motor)) << ": already there\n";
          if (g.json) std::cout << nlohmann::json{{"axes", {axis_to_json(*axis, s.model().motor(axis->motor))}}} << '\n';
          return static_cast<int>(kExitOk);
        }
        move = *planned->move;
        if (!planned->delay_us) move->delay_us = kDefaultDelayUs;
      } else {
        if (!o->microstep) o->microstep = axis->microstep;
        if (o->accel) {
          Result<uint32_t> steps = accel_steps(*axis, *o->accel, notes);
          if (!steps) return usage_error(g, steps.error().message);
          accel = *steps;
        }
        move = move_command(*o, s.model().motor(o->motor).microstep);
      }
      if (!move) return usage_error(g, move.error().message);
      for (const std::string& note : notes) {
        if (!g.json) std::cerr << "note: " << note << '\n';
      }
      if (accel) {
        if (s.firmware() == Firmware::kSeed) {
          return report_error(g, SessionError{SessionError::Kind::kRefused,
                                              "the seed firmware has no acceleration: move at a constant rate, or plan a "
                                              "staged ramp in a motion file",
                                              proto::Reason::kOk});
        }
        SessionResult<BoardFrame> set = s.execute(SetSetting{o->motor, proto::kSettingAccel, *accel});
        if (!set) return report_error(g, set.error());
      }
      if (o->wait) {
        if (SessionResult<Done> watched = watch_link(s, g); !watched) return report_error(g, watched.error());
      }
      SessionResult<BoardFrame> sent = s.execute(*move);
      if (!sent) return report_error(g, sent.error());
      if (o->wait) {
        const int code = wait_and_report(g, s, {o->motor}, Motion::kMove);
        if (!g.json && (o->to || o->by) && code != kExitInterrupted) {
          std::cout << axis_position_words(*axis, s.model().motor(o->motor)) << '\n';
        }
        return code;
      }
      if (g.json) {
        std::cout << nlohmann::json{{"started", command_to_json(*move)}} << '\n';
      } else {
        std::cout << (s.firmware() == Firmware::kSeed ? "sent (the original firmware confirms nothing): " : "started: ")
                  << describe(Command{*move}) << '\n';
      }
      return static_cast<int>(kExitOk);
    });
  });
}

// --- home, stop ---------------------------------------------------------------------------

void add_home(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string motors;
    uint32_t microstep = 0;
    uint32_t delay_us = 0;
    uint32_t max_steps = 0;
    bool no_wait = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("home", "home motors against their limit switch, one after another");
  cmd->add_option("motor", o->motors, "1, 2, an axis of the profile, or all (the motors with switches)")->required();
  cmd->add_option("--microstep", o->microstep, "microstep while seeking (default: keep the current one)");
  cmd->add_option("--delay", o->delay_us, "us per step while seeking (default: the board's home_seek_us)");
  cmd->add_option("--max-steps", o->max_steps, "give up after this many steps (default: no bound)");
  cmd->add_flag("--no-wait", o->no_wait, "start homing one motor and return");
  cmd->callback([&g, &exit_code, o] {
    // The command line first, with the switches every board of ours has; VER's list below.
    Result<const Profile*, int> profile_given = use_profile(g);
    if (!profile_given) {
      exit_code = profile_given.error();
      return;
    }
    std::vector<uint32_t> switched;
    for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
      if (proto::motor_has_switches(m)) switched.push_back(m);
    }
    Result<std::vector<uint32_t>> named = resolve_motors(o->motors, *profile_given, switched);
    if (!named) {
      exit_code = usage_error(g, named.error().message);
      return;
    }
    if (o->no_wait && named->size() > 1) {
      exit_code = usage_error(g, "--no-wait homes one motor: homing needs the others at rest");
      return;
    }
    if (!command_line_valid(g, StepperMove{named->front(), proto::kActionHome, o->microstep, o->max_steps, o->delay_us},
                            exit_code)) {
      return;
    }
    run_on_board(g, exit_code, [&](Session& s) {
      std::vector<uint32_t> with_switches;
      for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
        const bool has = s.version() ? ((s.version()->switch_mask >> (m - 1)) & 1u) != 0 : proto::motor_has_switches(m);
        if (has) with_switches.push_back(m);
      }
      const Profile* profile = profile_in_use(g);
      Result<std::vector<uint32_t>> motors = resolve_motors(o->motors, profile, with_switches);
      if (!motors) return usage_error(g, motors.error().message);
      if (o->no_wait && motors->size() > 1) return usage_error(g, "--no-wait homes one motor: homing needs the others at rest");
      // The seed firmware says nothing, so the end of a seek is known only from a step bound.
      const bool unbounded_seed = s.firmware() == Firmware::kSeed && o->max_steps == 0;
      if (unbounded_seed && motors->size() > 1) {
        return report_error(g, SessionError{SessionError::Kind::kRefused,
                                            "the original firmware does not say when a homing ends, and ignores a home "
                                            "while a motor moves: home one motor at a time once the last one rests, or "
                                            "give --max-steps so hmc can wait out each seek",
                                            proto::Reason::kMotorsRunning});
      }
      if (!o->no_wait) {
        if (SessionResult<Done> watched = watch_link(s, g); !watched) return report_error(g, watched.error());
      }
      // Homing needs every motor at rest (seed rule [2]): one after another.
      for (const uint32_t m : *motors) {
        StepperMove home{m, proto::kActionHome, o->microstep, o->max_steps, o->delay_us};
        if (const Axis* axis = profile != nullptr ? profile->axis_of_motor(m) : nullptr) {
          const HomingSetup setup = homing_setup(*axis, home);
          for (const SetSetting& set : setup.settings) {
            if (SessionResult<BoardFrame> done = s.execute(set); !done) return report_error(g, done.error());
          }
          home = setup.move;
        }
        SessionResult<BoardFrame> sent = s.execute(home);
        if (!sent) return report_error(g, sent.error());
        if (o->no_wait || unbounded_seed) {
          if (!g.json) {
            std::cout << "motor " << m
                      << (unbounded_seed ? ": home sent; the original firmware confirms nothing, nor when homing ends "
                                           "(--max-steps bounds the seek, and hmc waits it out)\n"
                                         : ": homing\n");
          }
          return static_cast<int>(kExitOk);
        }
        // The first motor that fails ends it: the next would home under the same fault.
        const int done = wait_and_report(g, s, {m}, Motion::kHome);
        if (done != kExitOk) return done;
        if (const Axis* axis = profile != nullptr ? profile->axis_of_motor(m) : nullptr) {
          if (Status limits = send_soft_limits(s, *axis); !limits) {
            return report_error(g, SessionError{SessionError::Kind::kNak, limits.error().message, proto::Reason::kOk});
          }
        }
      }
      return static_cast<int>(kExitOk);
    });
  });
}

void add_stop(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  auto motors_text = std::make_shared<std::string>("all");
  CLI::App* cmd = app.add_subcommand("stop", "stop motors (default: all)");
  cmd->add_option("motor", *motors_text, "1-3, an axis of the profile (several: 1,slide), or all");
  cmd->callback([&g, &exit_code, motors_text] {
    Result<const Profile*, int> profile = use_profile(g);
    if (!profile) {
      exit_code = profile.error();
      return;
    }
    Result<std::vector<uint32_t>> motors = resolve_motors(*motors_text, *profile, {1, 2, 3});
    if (!motors) {
      exit_code = usage_error(g, motors.error().message);
      return;
    }
    run_on_board(g, exit_code, [&](Session& s) {
      if (*motors_text == "all") {
        if (SessionResult<Done> stopped = s.stop_all(); !stopped) return report_error(g, stopped.error());
      } else {
        for (const uint32_t m : *motors) {
          SessionResult<BoardFrame> sent = s.execute(StepperMove{m, proto::kActionStop, 0, 0, 0});
          if (!sent) return report_error(g, sent.error());
        }
      }
      // A stop brakes when the motor ramps: report once it rests.
      return wait_and_report(g, s, *motors, Motion::kStop) == kExitIo ? static_cast<int>(kExitIo) : static_cast<int>(kExitOk);
    });
  });
}

// --- servo, led ---------------------------------------------------------------------------

void add_servo(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  auto move = std::make_shared<ServoMove>();
  CLI::App* cmd = app.add_subcommand("servo", "turn a servo to an angle");
  cmd->add_option("servo", move->servo, "1 (pan) or 2 (tilt)")->required();
  cmd->add_option("angle", move->angle, "degrees, 10-170 (90 is centre)")->required();
  cmd->callback([&g, &exit_code, move] {
    if (!command_line_valid(g, *move, exit_code)) return;
    run_on_board(g, exit_code, [&](Session& s) {
      for (const Warning& w : lint(Command{*move})) {
        if (!g.json) std::cerr << "warning: " << w.message << '\n';
      }
      SessionResult<BoardFrame> sent = s.execute(*move);
      if (!sent) return report_error(g, sent.error());
      if (g.json) {
        std::cout << nlohmann::json{{"servo", move->servo}, {"angle", move->angle},
                                    {"pulse_us", proto::servo_pulse_us(move->angle)}}
                  << '\n';
      } else {
        std::cout << describe(Command{*move}) << (s.firmware() == Firmware::kSeed ? kSeedIgnores : "") << '\n';
      }
      return static_cast<int>(kExitOk);
    });
  });
}

void add_led(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    uint32_t strip = 1;
    std::vector<std::string> colour;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("led", "set an LED strip's colour: R G B W (0-255), #RRGGBB[WW], or off");
  cmd->add_option("strip", o->strip, "1 or 2")->required();
  cmd->add_option("colour", o->colour, "R G B W, or #RRGGBBWW, or off")->required();
  cmd->callback([&g, &exit_code, o] {
    Result<LedColor> led = Error{"give the colour as R G B W (four numbers 0-255), #RRGGBB[WW], or off"};
    if (o->colour.size() == 1) {
      led = parse_led_colour(o->strip, o->colour[0]);
    } else if (o->colour.size() == 4) {
      std::vector<std::string> words{"LED", std::to_string(o->strip)};
      words.insert(words.end(), o->colour.begin(), o->colour.end());
      Result<Command, Diagnostic> command = command_from_words(words);
      if (!command) {
        exit_code = usage_error(g, command.error().message);
        return;
      }
      led = std::get<LedColor>(*command);
    }
    if (!led) {
      exit_code = usage_error(g, led.error().message);
      return;
    }
    if (!command_line_valid(g, *led, exit_code)) return;
    run_on_board(g, exit_code, [&](Session& s) {
      SessionResult<BoardFrame> sent = s.execute(*led);
      if (!sent) return report_error(g, sent.error());
      if (g.json) {
        std::cout << command_to_json(Command{*led}) << '\n';
      } else {
        std::cout << describe(Command{*led}) << (s.firmware() == Firmware::kSeed ? kSeedIgnores : "") << '\n';
      }
      return static_cast<int>(kExitOk);
    });
  });
}

// --- status, monitor ----------------------------------------------------------------------

std::string switches_words(const MotorStatus& m) {
  if (!proto::motor_has_switches(m.motor)) return "-";
  std::string w;
  if ((m.switches & 1u) != 0) w += "reverse ";
  if ((m.switches & 2u) != 0) w += "forward ";
  return w.empty() ? "open" : w.substr(0, w.size() - 1) + " pressed";
}

// "power-on", or why nothing is known.
std::string last_reset_words(const Session& s) {
  if (s.model().last_reset) return reset_text(*s.model().last_reset);
  const proto::FeatureSpec& spec = proto::feature_spec(proto::Feature::kResetCause);
  return "not reported (the board's firmware, protocol " + std::to_string(s.version() ? s.version()->protocol : 0) +
         ", predates it; protocol " + std::to_string(spec.since) + " reports it: reflash to see it)";
}

// "150000 steps/s together, 150000 while a motor ramps", or which part is assumed and why.
std::string step_budget_words(const Session& s) {
  const StepBudgets b = s.step_budgets_in_force();
  std::string out = std::to_string(b.constant) + " steps/s for the moving motors together, " +
                    std::to_string(b.ramping) + " while any of them ramps";
  if (s.supports(proto::Feature::kStepBudgets)) return out;
  const proto::FeatureSpec& spec = proto::feature_spec(proto::Feature::kStepBudgets);
  return out + " (the ramping budget is not reported by the board's firmware, protocol " +
         std::to_string(s.version() ? s.version()->protocol : 0) + "; protocol " + std::to_string(spec.since) +
         " reports it: reflash to see it)";
}

void print_status(const Session& s) {
  const BoardModel& model = s.model();
  if (s.firmware() == Firmware::kSeed) {
    std::cout << "The seed firmware reports nothing: the board's state is unknown to a new session.\n";
    return;
  }
  std::cout << "last reset: " << last_reset_words(s) << '\n';
  std::cout << "step budget: " << step_budget_words(s) << '\n';
  std::cout << "emergency switch: " << (model.board.emergency ? "PRESSED" : "released") << '\n';
  if (const std::optional<WatchdogStatus>& w = model.watchdog) {
    std::cout << "link watchdog: " << (w->timeout_ms == 0 ? std::string("off") : std::to_string(w->timeout_ms) + " ms")
              << (w->fired ? "; it FIRED since it was last armed: the host went silent and the board braked every "
                             "motor"
                           : "")
              << '\n';
  }
  std::cout << '\n';
  std::cout << std::left << std::setw(7) << "motor" << std::setw(10) << "state" << std::setw(14) << "position"
            << std::setw(14) << "target" << std::setw(11) << "microstep" << std::setw(9) << "rate" << std::setw(7)
            << "homed" << "switches\n";
  for (const MotorStatus& m : model.motors) {
    std::cout << std::left << std::setw(7) << m.motor << std::setw(10) << motor_state_name(m.state) << std::setw(14)
              << steps_text(m.position * m.microstep) << std::setw(14)
              << (m.endless ? std::string("(run)") : steps_text(m.target * m.microstep))
              << std::setw(11) << ("1/" + std::to_string(m.microstep)) << std::setw(9) << m.rate << std::setw(7)
              << (m.homed ? "yes" : "no") << switches_words(m) << '\n';
  }
  std::cout << "(positions in steps of the motor's microstep, as `hmc move` counts them; rate in steps/s)\n\n";
  const auto servo = [](uint32_t us) { return us == 0 ? std::string("released") : std::to_string(us) + " us"; };
  std::cout << "servo 1 (pan): " << servo(model.board.servo1_us) << "   servo 2 (tilt): " << servo(model.board.servo2_us)
            << '\n';
  for (const StripStatus& l : model.strips) {
    std::ostringstream hex;
    hex << '#' << std::hex << std::setfill('0') << std::setw(2) << l.r << std::setw(2) << l.g << std::setw(2) << l.b
        << std::setw(2) << l.w;
    std::cout << "strip " << l.strip << ": " << hex.str() << " (r " << l.r << ", g " << l.g << ", b " << l.b << ", w "
              << l.w << ")\n";
  }
}

void add_status(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("status", "the board's state: motors, switches, servos, LED strips");
  cmd->callback([&g, &exit_code] {
    run_on_board(g, exit_code, [&](Session& s) {
      const Profile* profile = profile_in_use(g);
      if (g.json) {
        nlohmann::json j = model_to_json(s);
        if (profile != nullptr) {
          j["axes"] = nlohmann::json::array();
          for (const Axis& a : profile->axes) j["axes"].push_back(axis_to_json(a, s.model().motor(a.motor)));
        }
        std::cout << j.dump(2) << '\n';
      } else {
        print_status(s);
        if (profile != nullptr && !profile->axes.empty() && s.firmware() == Firmware::kV2) {
          std::cout << "\naxes (" << profile->path << "):\n";
          for (const Axis& a : profile->axes) std::cout << "  " << axis_position_words(a, s.model().motor(a.motor)) << '\n';
        }
      }
      return static_cast<int>(kExitOk);
    });
  });
}

void add_monitor(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  auto seconds = std::make_shared<double>(0);
  CLI::App* cmd = app.add_subcommand("monitor", "show every reply and event the board sends, decoded, with times");
  cmd->add_option("--duration", *seconds, "stop after this many seconds (default: until Ctrl-C)")
      ->check(positive_number());
  cmd->callback([&g, &exit_code, seconds] {
    // Lines are shown as the session reads them, from when it is open (not its own queries).
    auto started = std::make_shared<Clock::time_point>();
    auto showing = std::make_shared<bool>(false);
    const LineHandler show = [&g, started, showing](std::string_view line, const Result<BoardFrame, Diagnostic>& frame) {
      if (!*showing) return;
      const double t = std::chrono::duration<double>(Clock::now() - *started).count();
      if (g.json) {
        nlohmann::json j{{"t", std::round(t * 1e6) / 1e6}, {"line", std::string(line)}};
        j["frame"] = frame ? board_frame_to_json(*frame) : nlohmann::json(nullptr);
        if (!frame) j["error"] = diagnostic_to_json(frame.error());
        std::cout << j << std::endl;
        return;
      }
      std::cout << std::fixed << std::setprecision(3) << "+" << t << " s  ";
      if (frame) {
        std::cout << board_frame_spec(*frame).name << ' ' << (is_event(*frame) ? "event" : "reply") << ": "
                  << describe(*frame) << std::endl;
      } else {
        std::cout << "not a frame: " << line << " (" << frame.error().message << ")" << std::endl;
      }
    };
    std::unique_ptr<Session> s = connect(g, exit_code, show);
    if (!s) return;
    if (s->firmware() == Firmware::kSeed && !g.json) std::cerr << "note: the seed firmware sends nothing\n";
    if (s->firmware() == Firmware::kV2 && !g.json) std::cerr << "the board's last reset: " << last_reset_words(*s) << "\n";
    if (SessionResult<Done> watched = watch_link(*s, g); !watched) {
      exit_code = report_error(g, watched.error());
      return;
    }
    if (!g.json) std::cerr << "listening" << (*seconds > 0 ? "" : " until Ctrl-C") << "...\n";
    *started = Clock::now();
    *showing = true;
    const auto duration = *seconds > 0 ? Millis{static_cast<int64_t>(*seconds * 1000)} : Millis{int64_t{1} << 40};
    if (SessionResult<Done> listened = s->listen(duration); !listened) exit_code = report_error(g, listened.error());
  });
}

}  // namespace

void add_board_commands(CLI::App& app, const GlobalOptions& global, int& exit_code) {
  add_send(app, global, exit_code);
  add_stream(app, global, exit_code);
  add_move(app, global, exit_code);
  add_home(app, global, exit_code);
  add_stop(app, global, exit_code);
  add_servo(app, global, exit_code);
  add_led(app, global, exit_code);
  add_status(app, global, exit_code);
  add_monitor(app, global, exit_code);
}

}  // namespace hmc::cli
