// `hmc jog`: keys read from a raw terminal become moves of the first three axes, with the
// positions redrawn on one status line.
#include "jog_command.h"

#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "axis_units.h"
#include "exit_codes.h"
#include "hmc/jog.h"
#include "hmc/units.h"
#include "profile_choice.h"

namespace hmc::cli {
namespace {

// The terminal in raw mode for as long as this lives; restore() (or the end of its life) puts
// back the modes it found, whichever way the command ends.
class RawTerminal {
 public:
  explicit RawTerminal(int fd) : fd_(fd) {
    if (tcgetattr(fd_, &saved_) != 0) return;
    termios raw = saved_;
    // No line editing, no echo, no signals from keys (Ctrl-C arrives as a byte), no flow control
    // or CR translation; output processing stays, so '\n' still starts a line.
    raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO | ISIG | IEXTEN);
    raw.c_iflag &= ~static_cast<tcflag_t>(IXON | ICRNL | INLCR | ISTRIP | BRKINT);
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    active_ = tcsetattr(fd_, TCSAFLUSH, &raw) == 0;
  }
  ~RawTerminal() { restore(); }
  RawTerminal(const RawTerminal&) = delete;
  RawTerminal& operator=(const RawTerminal&) = delete;
  bool active() const { return active_; }
  void restore() {
    if (!active_) return;
    tcsetattr(fd_, TCSAFLUSH, &saved_);
    active_ = false;
  }

 private:
  int fd_;
  termios saved_{};
  bool active_ = false;
};

struct JogAxis {
  Axis axis;
  bool from_profile = false;
  std::optional<double> target;  // axis units: the end of the jog under way
};

class Jogger {
 public:
  Jogger(Session& s, const Profile* profile) : s_(s) {
    for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
      const Axis* described = profile != nullptr ? profile->axis_of_motor(m) : nullptr;
      Result<Axis> axis = resolve_axis(std::to_string(m), profile, s.model());
      axes_.push_back({described != nullptr ? *described : *axis, described != nullptr, std::nullopt});
    }
  }

  // Carries out one key; a session error (the link lost, a refusal it cannot explain) ends the jog.
  SessionResult<Done> apply(const JogKey& key) {
    switch (key.kind) {
      case JogKey::Kind::kStepUp: level_ = std::min<size_t>(level_ + 1, kJogProfileSteps.size() - 1); return Done{};
      case JogKey::Kind::kStepDown: level_ = level_ == 0 ? 0 : level_ - 1; return Done{};
      case JogKey::Kind::kStopAll:
        for (JogAxis& a : axes_) a.target.reset();
        message_ = "stopped";
        return s_.stop_all();
      case JogKey::Kind::kZero: return zero();
      case JogKey::Kind::kMove: return move(key);
      default: return Done{};
    }
  }

  std::string status_line() {
    std::ostringstream line;
    for (size_t i = 0; i < axes_.size(); ++i) {
      const JogAxis& a = axes_[i];
      const MotorStatus& m = s_.model().motor(a.axis.motor);
      line << (i == last_ ? "*" : "") << a.axis.name << ' ';
      if (a.from_profile) {
        line << number_text(a.axis.from_board_position(m.position)) << " " + std::string(unit_name(a.axis.unit()));
      } else {
        line << number_text(static_cast<double>(m.position) * m.microstep / 256.0) << " steps";
      }
      line << "  ";
    }
    line << "step " << step_words(axes_[last_]);
    if (!message_.empty()) line << "  | " << message_;
    return line.str();
  }

 private:
  double step_units(const JogAxis& a) const {
    if (a.from_profile) return kJogProfileSteps[level_];
    return kJogMotorSteps[level_] / a.axis.steps_per_unit();
  }
  std::string step_words(const JogAxis& a) const {
    if (a.from_profile) return number_text(kJogProfileSteps[level_]) + " " + std::string(unit_name(a.axis.unit()));
    return number_text(kJogMotorSteps[level_]) + " steps";
  }

  SessionResult<Done> move(const JogKey& key) {
    last_ = key.axis;
    JogAxis& a = axes_[key.axis];
    const MotorStatus& motor = s_.model().motor(a.axis.motor);
    const bool moving = motor.state != MotorState::kIdle;
    const double here = a.axis.from_board_position(motor.position);
    const JogEnd end = jog_end(a.axis, motor, moving && a.target ? *a.target : here,
                               key.dir * step_units(a) * (key.fast ? kJogShiftFactor : 1));
    const double target = end.target;
    message_ = end.at_limit ? a.axis.name + " stops at its soft limit " + number_text(target) + " " + unit_name(a.axis.unit()) : "";
    if (moving) {
      if (SessionResult<Done> stopped = s_.stop({a.axis.motor}); !stopped) return stopped;
    }
    const std::string unit = unit_name(a.axis.unit());
    Result<UnitMove> planned = unit_move(a.axis, s_.model().motor(a.axis.motor),
                                         UnitMoveRequest{number_text(target, 6) + unit, std::nullopt, std::nullopt, std::nullopt});
    if (!planned) {
      message_ = planned.error().message;
      return Done{};
    }
    a.target = target;
    if (!planned->move) return Done{};
    StepperMove m = *planned->move;
    if (!planned->delay_us) m.delay_us = kDefaultMoveDelayUs;
    if (planned->accel && s_.firmware() == Firmware::kV2) {
      if (SessionResult<BoardFrame> set = s_.execute(SetSetting{m.motor, proto::kSettingAccel, *planned->accel}); !set) {
        return set.error();
      }
    }
    if (SessionResult<BoardFrame> sent = s_.execute(m); !sent) {
      if (sent.error().kind != SessionError::Kind::kRefused && sent.error().kind != SessionError::Kind::kNak) return sent.error();
      message_ = sent.error().message;  // a pressed switch, the emergency switch: said, not fatal
    }
    return Done{};
  }

  SessionResult<Done> zero() {
    JogAxis& a = axes_[last_];
    if (SessionResult<Done> able = s_.require(proto::Feature::kSetPosition); !able) {
      message_ = able.error().message;
      return Done{};
    }
    if (s_.model().motor(a.axis.motor).state != MotorState::kIdle) {
      message_ = a.axis.name + " is moving: stop it (space) before zeroing";
      return Done{};
    }
    if (SessionResult<BoardFrame> done = s_.execute(set_position_command(a.axis, 0)); !done) return done.error();
    a.target.reset();
    if (Status limits = send_soft_limits(s_, a.axis); !limits) {
      message_ = limits.error().message;
      return Done{};
    }
    message_ = a.axis.name + " zeroed here";
    return Done{};
  }

  Session& s_;
  std::vector<JogAxis> axes_;
  size_t level_ = kJogFirstStep;
  size_t last_ = 0;
  std::string message_;
};

// The jog until q, Ctrl-C, a signal, the end of input or a session error; the exit code.
int jog_loop(const GlobalOptions& g, Session& s, const Profile* profile) {
  Jogger jogger(s, profile);
  std::string pending;
  std::string shown;
  const auto draw = [&] {
    const std::string line = jogger.status_line();
    if (line == shown) return;
    shown = line;
    std::cout << "\r\x1b[K" << line << std::flush;
  };
  std::cout << "hmc jog: arrows, Page Up/Down (Shift: 10x), +/- step, space stop, z zero, q quit\n";
  draw();
  while (true) {
    if (interrupt_requested()) return kExitInterrupted;
    pollfd in{STDIN_FILENO, POLLIN, 0};
    const int ready = poll(&in, 1, 30);
    if (ready < 0 && errno != EINTR) return report_error(g, SessionError{SessionError::Kind::kLink, "reading the terminal failed", proto::Reason::kOk});
    if (ready > 0) {
      char buffer[64];
      const ssize_t got = read(STDIN_FILENO, buffer, sizeof buffer);
      if (got <= 0 && (in.revents & (POLLHUP | POLLERR)) != 0) return kExitOk;  // the terminal went away
      if (got > 0) pending.append(buffer, static_cast<size_t>(got));
      for (const JogKey& key : decode_jog_keys(pending)) {
        if (key.kind == JogKey::Kind::kQuit) return kExitOk;
        if (key.kind == JogKey::Kind::kInterrupt) return kExitInterrupted;
        if (SessionResult<Done> done = jogger.apply(key); !done) {
          std::cout << "\r\n";
          return report_error(g, done.error());
        }
        draw();
      }
    }
    if (SessionResult<Done> heard = s.listen(Millis{10}); !heard) {
      std::cout << "\r\n";
      return report_error(g, heard.error());
    }
    draw();
  }
}

}  // namespace

void add_jog_command(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "jog", "move the steppers from the keyboard: arrows, Page Up/Down, Shift 10x, +/- step, space stop, z zero, q quit");
  cmd->callback([&g, &exit_code] {
    if (isatty(STDIN_FILENO) == 0) {
      report_error(g, SessionError{SessionError::Kind::kInvalid, "hmc jog reads keys from a terminal: standard input is not one",
                                   proto::Reason::kOk});
      exit_code = kExitUsage;
      return;
    }
    Result<const Profile*, int> profile = use_profile(g);
    if (!profile) {
      exit_code = profile.error();
      return;
    }
    std::unique_ptr<Session> s = connect(g, exit_code);
    if (!s) return;
    if (SessionResult<Done> watched = watch_link(*s, g); !watched) {
      exit_code = report_error(g, watched.error());
      return;
    }
    int code = kExitOk;
    {
      RawTerminal terminal(STDIN_FILENO);
      if (!terminal.active()) {
        exit_code = report_error(g, SessionError{SessionError::Kind::kLink, "cannot put the terminal in raw mode", proto::Reason::kOk});
        return;
      }
      code = jog_loop(g, *s, *profile);
      terminal.restore();
    }
    std::cout << '\n';
    // Every motor stopped, whichever way the jog ended; over a lost link only the board's watchdog can.
    if (SessionResult<Done> stopped = s->stop_all(); !stopped) {
      if (code == kExitOk) {
        code = report_error(g, stopped.error());
      } else if (!g.json) {
        std::cerr << "the stop could not be sent (" << stopped.error().message << ")"
                  << (s->watchdog_armed() ? "; the board's link watchdog stops the motors" : "") << '\n';
      }
    } else if (!g.json) {
      std::cerr << (code == kExitInterrupted ? "interrupted; " : "") << "every motor was sent a stop\n";
    }
    exit_code = code;
  });
}

}  // namespace hmc::cli
