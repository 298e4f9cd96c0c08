// The grbl front end: grbl's line protocol and state machine over a Session (grbl.h): the
// sender's bytes, real-time commands, `$` commands and G-code lines. Moves on the board are in
// grbl_motion.cpp, status reports and settings in grbl_reports.cpp.
#include "grbl_shared.h"

#include <cmath>
#include <cstdlib>

namespace hmc::grbl {

using namespace detail;

const char* state_name(State state) {
  switch (state) {
    case State::kIdle: return "Idle";
    case State::kRun: return "Run";
    case State::kHold: return "Hold";
    case State::kJog: return "Jog";
    case State::kHome: return "Home";
    case State::kAlarm: return "Alarm";
  }
  return "Idle";
}

Result<std::array<std::optional<Axis>, kAxisCount>> map_axes(const Profile* profile) {
  std::array<std::optional<Axis>, kAxisCount> axes;
  if (profile == nullptr) {
    for (size_t a = 0; a < kAxisCount; ++a) {
      Axis axis;
      axis.name = std::string(1, static_cast<char>(kLetters[a] - 'A' + 'a'));
      axis.motor = static_cast<uint32_t>(a + 1);
      axis.mm_per_rev = 40;
      axes[a] = axis;
    }
    return axes;
  }
  bool named = false;
  for (const Axis& axis : profile->axes) {
    for (size_t a = 0; a < kAxisCount; ++a) {
      if (axis.name.size() == 1 && (axis.name[0] == kLetters[a] || axis.name[0] == kLetters[a] - 'A' + 'a')) {
        axes[a] = axis;
        named = true;
      }
    }
  }
  if (!named) {
    size_t a = 0;
    for (const Axis& axis : profile->axes) {  // by motor number already
      if (a < kAxisCount) axes[a++] = axis;
    }
  }
  bool any = false;
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (!axes[a]) continue;
    any = true;
    if (axes[a]->rotary) {
      return Error{"axis '" + axes[a]->name + "' (" + kLetters[a] +
                   ") is rotary: G-code's X, Y and Z are linear, in mm (name the linear axes x, y and z in the profile)"};
    }
  }
  if (!any) return Error{"the profile has no axis for X, Y or Z"};
  return axes;
}

FrontEnd::FrontEnd(Session& session, const std::array<std::optional<Axis>, kAxisCount>& axes) : session_(session) {
  for (size_t a = 0; a < kAxisCount; ++a) {
    GrblAxis& g = axes_[a];
    g.axis = axes[a];
    if (!g.axis) continue;
    const double spu = g.axis->steps_per_unit();
    g.max_rate = (g.axis->speed ? *g.axis->speed : kDefaultRate / spu) * 60.0;
    g.accel = g.axis->accel ? *g.axis->accel : kDefaultAccel / spu;
    if (g.axis->limit_min && g.axis->limit_max) {
      g.max_travel = *g.axis->limit_max - *g.axis->limit_min;
      soft_limits_ = true;
    }
    if (g.axis->homing && g.axis->motor <= 2) homing_ = true;
  }
  // grbl with homing enabled starts locked until homed; here only while an axis that homes is
  // not homed on the board (a board that stayed powered keeps its reference).
  if (homing_) {
    for (const GrblAxis& g : axes_) {
      if (g.axis && g.axis->homing && !session_.model().motor(g.axis->motor).homed) state_ = State::kAlarm;
    }
  }
  resync();
}

bool FrontEnd::homing_enabled() const { return homing_; }

int64_t FrontEnd::microsteps(size_t a) const {
  const Axis& axis = *axes_[a].axis;
  const MotorStatus& m = session_.model().motor(axis.motor);
  const auto v = static_cast<int64_t>(std::llround(static_cast<double>(m.position) * axis.microstep / 256.0));
  return axis.invert ? -v : v;
}

double FrontEnd::machine_mm(size_t a) const {
  if (!axes_[a].axis) return 0;
  return static_cast<double>(microsteps(a)) / axes_[a].axis->steps_per_unit();
}

void FrontEnd::resync() {
  Vec3 machine{};
  for (size_t a = 0; a < kAxisCount; ++a) machine[a] = machine_mm(a);
  interpreter_.set_position(machine);
}

void FrontEnd::connected() {
  out_.clear();
  send("");
  send(kBanner);
  if (lost_sender_during_motion_) {
    message("the last sender went away during a motion: every motor was stopped");
    lost_sender_during_motion_ = false;
  }
  if (state_ == State::kAlarm) message("'$H'|'$X' to unlock");
}

void FrontEnd::receive(std::string_view bytes) {
  for (const char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '?': status_requested_ = true; continue;
      case '!': hold_requested_ = true; continue;
      case '~': resume_requested_ = true; continue;
      case 0x18: reset_requested_ = true; continue;
      case 0x85: jog_cancel_requested_ = true; continue;
      default: break;
    }
    if (c >= 0x84 && c <= 0xA1) {  // grbl's other real-time commands: door, overrides, toggles
      realtime_notes_.push_back("real-time command 0x" + std::string(1, "0123456789ABCDEF"[c >> 4]) +
                                std::string(1, "0123456789ABCDEF"[c & 15]) +
                                " (safety door, overrides) is not supported by this front end");
      continue;
    }
    if (c == '\n' || c == '\r') {
      // CR, LF and CRLF each end one line; an empty line is answered `ok`, as grbl does.
      const bool crlf = c == '\n' && last_was_cr_;
      last_was_cr_ = c == '\r';
      if (!crlf) lines_.push_back(partial_overflow_ ? std::string(kLineMax + 1, 'X') : partial_);
      partial_.clear();
      partial_overflow_ = false;
      continue;
    }
    last_was_cr_ = false;
    // A sender that never ends its line gets error 11 when it does, not unbounded memory here.
    if (partial_.size() < 4 * kRxBufferSize) {
      partial_.push_back(ch);
    } else {
      partial_overflow_ = true;
    }
  }
}

std::string FrontEnd::take_output() {
  std::string out;
  out.swap(out_);
  return out;
}

void FrontEnd::error(const GrblError& e) {
  if (!e.message.empty()) message(e.message);
  send("error:" + std::to_string(e.code));
}

SessionResult<Done> FrontEnd::service() {
  if (SessionResult<Done> heard = session_.listen(Millis{1}); !heard) return heard;
  if (SessionResult<Done> rt = realtime(); !rt) return rt;
  const bool emergency = session_.model().board.emergency;
  if (emergency && !emergency_seen_) {
    emergency_seen_ = true;
    if (SessionResult<Done> a = alarm(3, "the emergency switch is pressed: every motor stopped"); !a) return a;
  } else if (!emergency && emergency_seen_) {
    emergency_seen_ = false;
    message("the emergency switch was released: '$X' to unlock");
  }
  if (SessionResult<Done> moved = advance(); !moved) return moved;
  while (!lines_.empty() && !sync_pending_ && queue_.size() < kPlannerBlocks) {
    const std::string raw = lines_.front();
    lines_.pop_front();
    line(raw);
  }
  return advance();
}

SessionResult<Done> FrontEnd::realtime() {
  for (const std::string& note : realtime_notes_) message(note);
  realtime_notes_.clear();
  if (reset_requested_) {
    reset_requested_ = false;
    hold_requested_ = resume_requested_ = jog_cancel_requested_ = false;
    const bool in_motion = current_.has_value() || session_.model().any_moving();
    if (SessionResult<Done> stopped = stop(); !stopped) return stopped;
    lines_.clear();
    interpreter_.reset_modal();
    if (in_motion && state_ != State::kAlarm) {
      state_ = State::kAlarm;
      send("ALARM:3");
      message("reset during a motion: every motor was stopped");
    } else if (state_ != State::kAlarm) {
      state_ = State::kIdle;
    }
    send("");
    send(kBanner);
    if (state_ == State::kAlarm) message("'$H'|'$X' to unlock");
  }
  if (jog_cancel_requested_) {
    jog_cancel_requested_ = false;
    if (state_ == State::kJog) {
      if (SessionResult<Done> stopped = stop(); !stopped) return stopped;
      state_ = State::kIdle;
    }
  }
  if (hold_requested_) {
    hold_requested_ = false;
    if (state_ == State::kJog) {  // grbl: a feed hold cancels a jog
      if (SessionResult<Done> stopped = stop(); !stopped) return stopped;
      state_ = State::kIdle;
    } else if (state_ == State::kRun || (state_ == State::kIdle && !queue_.empty())) {
      state_ = State::kHold;
      hold_stopped_ = false;
      if (SessionResult<Done> braking = stop_moving(); !braking) return braking;
    }
  }
  if (resume_requested_) {
    resume_requested_ = false;
    if (state_ == State::kHold && hold_stopped_) {
      state_ = State::kRun;
      if (current_ && std::holds_alternative<Pause>(*current_)) current_.reset();
      current_started_ = false;  // a segment held mid-way starts again from where it stopped
    }
  }
  if (status_requested_) {
    status_requested_ = false;
    return status_report();
  }
  return Done{};
}

SessionResult<Done> FrontEnd::stop_moving() {
  std::vector<Command> stops;
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (moving(session_.model().motor(m))) stops.emplace_back(StepperMove{m, proto::kActionStop, 0, 0, 0});
  }
  if (stops.empty()) return Done{};
  SessionResult<Session::StreamReport> sent = session_.stream(stops);
  if (!sent) return sent.error();
  return Done{};
}

SessionResult<Done> FrontEnd::stop() {
  drop_queue();
  if (session_.model().any_moving()) {
    if (SessionResult<Done> stopped = session_.stop_all(); !stopped) return stopped;
  }
  resync();
  return Done{};
}

void FrontEnd::drop_queue() {
  queue_.clear();
  current_.reset();
  current_started_ = false;
  homing_left_.clear();
  sync_pending_ = false;
}

SessionResult<Done> FrontEnd::sender_gone() {
  const bool in_motion = current_.has_value() || !queue_.empty() || session_.model().any_moving();
  if (SessionResult<Done> stopped = stop(); !stopped) return stopped;
  lines_.clear();
  partial_.clear();
  out_.clear();
  status_requested_ = hold_requested_ = resume_requested_ = reset_requested_ = jog_cancel_requested_ = false;
  interpreter_.reset_modal();
  if (in_motion) {
    lost_sender_during_motion_ = true;
    state_ = State::kAlarm;
  } else if (state_ != State::kAlarm) {
    state_ = State::kIdle;
  }
  return Done{};
}

SessionResult<Done> FrontEnd::alarm(int code, const std::string& why) {
  const bool failed_sync = sync_pending_;
  drop_queue();
  lines_.clear();
  if (session_.model().any_moving()) {
    if (SessionResult<Done> stopped = session_.stop_all(); !stopped) return stopped;
  }
  resync();
  state_ = State::kAlarm;
  send("ALARM:" + std::to_string(code));
  message(why);
  if (failed_sync) send("error:" + std::to_string(kSystemGcLock));
  return Done{};
}

// ---- lines ---------------------------------------------------------------------------------

void FrontEnd::line(const std::string& raw) {
  const CleanLine clean = clean_line(raw);
  if (clean.stored > kLineMax) {
    error(GrblError{kOverflow, "line longer than grbl's " + std::to_string(kLineMax) + " characters"});
    return;
  }
  if (clean.garbage) {
    error(*clean.garbage);
    return;
  }
  if (clean.text.empty()) {
    ok();
    return;
  }
  if (clean.text[0] == '$') {
    system_command(clean.text);
    return;
  }
  if (state_ == State::kAlarm) {
    error(GrblError{kSystemGcLock, "G-code is locked out during an alarm: '$H' homes, '$X' unlocks"});
    return;
  }
  gcode(clean.text, false);
}

void FrontEnd::system_command(const std::string& c) {
  if (c == "$") {
    send("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]");
  } else if (c == "$$") {
    out_ += settings_text();
  } else if (c == "$#") {
    out_ += parameters_text();
  } else if (c == "$G") {
    send(interpreter_.parser_state());
  } else if (c == "$I") {
    send("[VER:1.1h.hmc:]");
    send("[OPT:V," + std::to_string(kPlannerBlocks) + "," + std::to_string(kRxBufferSize) + "]");
    message("hmc grbl front end on " + session_.description());
  } else if (c == "$N") {
    send("$N0=");
    send("$N1=");
  } else if (c == "$X") {
    if (state_ == State::kAlarm) {
      if (session_.model().board.emergency) {
        error(GrblError{kSystemGcLock, "the emergency switch is still pressed"});
        return;
      }
      message("Caution: Unlocked");
      state_ = State::kIdle;
      resync();
    }
  } else if (c == "$H") {
    if (!homing_) {
      error(GrblError{kSettingDisabled, "homing is disabled ($22=0), or no axis of the profile homes"});
      return;
    }
    if (state_ != State::kIdle && state_ != State::kAlarm) {
      error(GrblError{kIdleError, "homing needs the machine at rest"});
      return;
    }
    if (session_.model().board.emergency) {
      error(GrblError{kSystemGcLock, "the emergency switch is pressed"});
      return;
    }
    state_ = State::kIdle;
    queue_.emplace_back(Home{});
    sync_pending_ = true;
    return;
  } else if (c.rfind("$J=", 0) == 0) {
    if (state_ != State::kIdle && state_ != State::kJog) {
      error(GrblError{state_ == State::kAlarm ? kSystemGcLock : kIdleError,
                      std::string("a jog needs the machine idle or jogging, not ") + state_name(state_)});
      return;
    }
    gcode(c.substr(3), true);
    return;
  } else if (c.size() > 1 && c[1] >= '0' && c[1] <= '9') {
    setting(c);
    return;
  } else if (c == "$C" || c == "$SLP" || c.rfind("$RST=", 0) == 0 || c.rfind("$N0=", 0) == 0 || c.rfind("$N1=", 0) == 0) {
    error(GrblError{kInvalidStatement, c + ": not supported by this front end (check mode, sleep, restoring settings, startup lines)"});
    return;
  } else {
    error(GrblError{kInvalidStatement, c + ": not a '$' command ('$' lists them)"});
    return;
  }
  ok();
}

void FrontEnd::gcode(const std::string& clean, bool jog) {
  const Interpreter before = interpreter_;
  GrblResult<std::vector<Step>> steps = interpreter_.interpret(clean, jog);
  if (!steps) {
    error(steps.error());
    return;
  }
  std::vector<Action> actions;
  bool sync = false;
  for (const Step& step : *steps) {
    if (const auto* move = std::get_if<Move>(&step)) {
      for (size_t a = 0; a < kAxisCount; ++a) {
        if (!axes_[a].axis && std::fabs(move->target[a] - before.position()[a]) > 1e-9) {
          interpreter_ = before;
          error(GrblError{kUnsupportedCommand, std::string(1, kLetters[a]) + ": the profile has no axis for it"});
          return;
        }
      }
      if (std::optional<std::string> why = beyond_limits(move->target)) {
        interpreter_ = before;
        if (jog) {
          error(GrblError{kJogTravel, *why});
        } else {
          (void)alarm(2, *why);  // a lost link shows at the next service()
          send("error:" + std::to_string(kSystemGcLock));
        }
        return;
      }
      Segment s;
      for (size_t a = 0; a < kAxisCount; ++a) {
        if (axes_[a].axis) s.target[a] = std::llround(move->target[a] * axes_[a].axis->steps_per_unit());
      }
      s.rapid = move->rapid;
      s.feed = move->feed;
      s.jog = jog;
      actions.emplace_back(s);
    } else if (const auto* dwell = std::get_if<grbl::Dwell>(&step)) {
      actions.emplace_back(Dwell{dwell->seconds});
      sync = true;  // grbl answers a dwell once it is over
    } else if (const auto* servo = std::get_if<ServoCommand>(&step)) {
      actions.emplace_back(BoardCommand{ServoMove{servo->servo, servo->angle}});
    } else if (const auto* led = std::get_if<LedCommand>(&step)) {
      actions.emplace_back(BoardCommand{LedColor{led->strip, led->r, led->g, led->b, led->w}});
    } else if (std::holds_alternative<ProgramPause>(step)) {
      actions.emplace_back(Pause{});
    } else if (std::holds_alternative<ProgramEnd>(step)) {
      actions.emplace_back(End{});
      sync = true;  // grbl answers M2/M30 once every move before it is done
    }
  }
  for (Action& a : actions) queue_.push_back(std::move(a));
  if (sync) {
    sync_pending_ = true;
  } else {
    ok();
  }
}

std::optional<std::string> FrontEnd::beyond_limits(const Vec3& machine) const {
  if (!soft_limits_) return std::nullopt;
  for (size_t a = 0; a < kAxisCount; ++a) {
    const GrblAxis& g = axes_[a];
    if (!g.axis || !g.axis->limit_min || !session_.model().motor(g.axis->motor).homed) continue;
    const double low = *g.axis->limit_min, high = *g.axis->limit_min + g.max_travel;
    if (machine[a] < low - 1e-6 || machine[a] > high + 1e-6) {
      return std::string(1, kLetters[a]) + " " + fmt(machine[a]) + " mm (machine) is beyond its soft limits, " + fmt(low) +
             " to " + fmt(high) + " mm";
    }
  }
  return std::nullopt;
}
}  // namespace hmc::grbl
