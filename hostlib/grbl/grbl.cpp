// The grbl front end: grbl's line protocol and state machine over a Session (grbl.h).
#include "hmc/grbl.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "hmc/axis_moves.h"

namespace hmc::grbl {
namespace {

constexpr double kMmPerInch = 25.4;
// Rates: every motor's under the board's budget for motors stepping at once while one ramps
// (docs/motion-files.md: 40 000 steps/s; 50 000 at constant rate).
constexpr double kRampBudget = 40000;
constexpr double kFlatBudget = 50000;
// Without a profile speed or acceleration: one turn of a 200-step motor at 1/16 per second, and
// that rate reached in a quarter of a second.
constexpr double kDefaultRate = 3200;   // steps/s
constexpr double kDefaultAccel = 12800;  // steps/s^2

const char kLetters[kAxisCount] = {'X', 'Y', 'Z'};

bool moving(const MotorStatus& m) { return m.state != MotorState::kIdle; }

std::string fmt(double v, int decimals = 3) { return fixed(v, decimals); }

}  // namespace

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

// ---- motion --------------------------------------------------------------------------------

SessionResult<Done> FrontEnd::advance() {
  if (state_ == State::kHold && !hold_stopped_ && !session_.model().any_moving()) hold_stopped_ = true;
  for (int guard = 0; guard < 64; ++guard) {
    if (current_) {
      if (!current_started_) {
        if (state_ == State::kHold || state_ == State::kAlarm) return Done{};
        SessionResult<bool> began = start(*current_);
        if (!began) return began.error();
        if (!current_) continue;  // an alarm dropped it
        current_started_ = true;
      }
      SessionResult<bool> over = finished(*current_);
      if (!over) return over.error();
      if (!current_) continue;
      if (!*over) return Done{};
      current_.reset();
      current_started_ = false;
      continue;
    }
    if (state_ == State::kHold || state_ == State::kAlarm) return Done{};
    if (queue_.empty()) {
      if (state_ == State::kRun || state_ == State::kJog || state_ == State::kHome) state_ = State::kIdle;
      if (sync_pending_) sync_ok();
      return Done{};
    }
    current_ = std::move(queue_.front());
    queue_.pop_front();
    current_started_ = false;
  }
  return Done{};
}

void FrontEnd::sync_ok() {
  sync_pending_ = false;
  ok();
}

SessionResult<bool> FrontEnd::start(Action& action) {
  if (const auto* s = std::get_if<Segment>(&action)) {
    if (state_ == State::kIdle) state_ = s->jog ? State::kJog : State::kRun;
    if (SessionResult<Done> started = start_segment(*s); !started) return started.error();
    return true;
  }
  if (const auto* d = std::get_if<Dwell>(&action)) {
    dwell_until_ = Clock::now() + std::chrono::microseconds(std::llround(d->seconds * 1e6));
    return true;
  }
  if (auto* b = std::get_if<BoardCommand>(&action)) {
    SessionResult<BoardFrame> done = session_.execute(b->command);
    if (!done) {
      if (done.error().kind == SessionError::Kind::kLink || done.error().kind == SessionError::Kind::kNoReply) {
        return done.error();
      }
      message("the board refused " + describe(b->command) + ": " + done.error().message);
    }
    return true;
  }
  if (std::holds_alternative<Pause>(action)) {
    state_ = State::kHold;
    hold_stopped_ = true;
    message("Pgm Pause: '~' resumes");
    return false;
  }
  if (std::holds_alternative<Home>(action)) {
    state_ = State::kHome;
    homing_left_.clear();
    for (size_t a : {size_t{2}, size_t{0}, size_t{1}}) {  // grbl homes Z first, then X and Y
      if (axes_[a].axis && axes_[a].axis->homing && axes_[a].axis->motor <= 2) homing_left_.push_back(a);
    }
    if (SessionResult<Done> next = home_next(); !next) return next.error();
    return true;
  }
  return true;  // End
}

SessionResult<Done> FrontEnd::home_next() {
  const size_t a = homing_left_.front();
  const Axis& axis = *axes_[a].axis;
  const HomingSetup setup = homing_setup(axis, StepperMove{axis.motor, proto::kActionHome, 0, 0, 0});
  // grbl owns the board while it runs: a pull-off or slow re-approach the profile leaves out is
  // set to 0 (none), not left as an earlier session set it.
  std::vector<Command> commands;
  for (const uint32_t setting : {proto::kSettingHomeEnd, proto::kSettingHomePullOff, proto::kSettingHomeLocate}) {
    const auto given = std::find_if(setup.settings.begin(), setup.settings.end(),
                                    [setting](const SetSetting& s) { return s.setting == setting; });
    commands.emplace_back(given != setup.settings.end() ? *given : SetSetting{axis.motor, setting, 0});
  }
  commands.emplace_back(setup.move);
  SessionResult<Session::StreamReport> sent = session_.stream(commands);
  if (!sent) return sent.error();
  if (sent->refused) return alarm(9, std::string(1, kLetters[a]) + ": homing was refused: " + sent->why);
  current_motors_ = {axis.motor};
  return Done{};
}

SessionResult<Done> FrontEnd::start_segment(const Segment& s) {
  std::array<int64_t, kAxisCount> delta{};
  double length_sq = 0;
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (!axes_[a].axis) continue;
    delta[a] = s.target[a] - microsteps(a);
    const double mm = static_cast<double>(delta[a]) / axes_[a].axis->steps_per_unit();
    length_sq += mm * mm;
  }
  current_motors_.clear();
  const double length = std::sqrt(length_sq);
  if (length <= 0) return Done{};
  // One speed V and acceleration A along the path, each axis its share u = d/D of both: the
  // slowest axis's limits bound V and A (grbl's planner does the same).
  double speed = s.rapid ? 1e300 : s.feed / 60.0;
  double accel = 1e300;
  double steps_per_mm_path = 0;  // total step rate per mm/s of path speed
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (delta[a] == 0) continue;
    const GrblAxis& g = axes_[a];
    const double u = std::fabs(static_cast<double>(delta[a]) / g.axis->steps_per_unit()) / length;
    speed = std::min(speed, g.max_rate / 60.0 / u);
    accel = std::min(accel, g.accel / u);
    steps_per_mm_path += u * g.axis->steps_per_unit();
  }
  const double budget = accel > 0 ? kRampBudget : kFlatBudget;
  speed = std::min(speed, budget / steps_per_mm_path);
  std::vector<Command> setup, moves;
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (delta[a] == 0) continue;
    const Axis& axis = *axes_[a].axis;
    const double u = std::fabs(static_cast<double>(delta[a]) / axis.steps_per_unit()) / length;
    const double rate = speed * u * axis.steps_per_unit();  // steps/s
    const auto delay = static_cast<uint32_t>(std::clamp(std::llround(1e6 / rate), 1LL, 2147483647LL));
    uint32_t a_steps = 0;
    if (accel > 0) a_steps = static_cast<uint32_t>(std::clamp(std::llround(accel * u * axis.steps_per_unit()), 1LL, 2000000LL));
    if (accel_sent_[axis.motor - 1] != a_steps) {
      setup.emplace_back(SetSetting{axis.motor, proto::kSettingAccel, a_steps});
      accel_sent_[axis.motor - 1] = a_steps;
    }
    const bool forward = (delta[a] > 0) != axis.invert;
    moves.emplace_back(StepperMove{axis.motor, forward ? proto::kActionForward : proto::kActionReverse, axis.microstep,
                                   static_cast<uint32_t>(std::llabs(delta[a])), delay});
    current_motors_.push_back(axis.motor);
  }
  // The accelerations, then the moves, all sent without waiting for replies: the STM lines
  // follow each other on the wire, so the axes start one line's wire time apart (docs/grbl.md).
  std::vector<Command> lines = setup;
  lines.insert(lines.end(), moves.begin(), moves.end());
  SessionResult<Session::StreamReport> sent = session_.stream(lines);
  if (!sent) return sent.error();
  if (sent->refused) {
    accel_sent_ = {};
    const bool soft = sent->why.find("soft") != std::string::npos;
    return alarm(soft ? 2 : 3, "the board refused the move: " + sent->why);
  }
  return Done{};
}

SessionResult<bool> FrontEnd::finished(Action& action) {
  const BoardModel& model = session_.model();
  if (std::holds_alternative<Segment>(action) || std::holds_alternative<Home>(action)) {
    for (uint32_t m : current_motors_) {
      if (moving(model.motor(m))) return false;
    }
    for (uint32_t m : current_motors_) {
      const std::optional<MotionEnd>& end = model.last_end[m - 1];
      if (end == MotionEnd::kLimit) {
        (void)alarm(1, "motor " + std::to_string(m) + " reached a limit switch: every motor stopped");
        return false;
      }
      if (end == MotionEnd::kEmergency || end == MotionEnd::kWatchdog) {
        (void)alarm(3, "motor " + std::to_string(m) + (end == MotionEnd::kEmergency ? " stopped by the emergency switch"
                                                                                    : " stopped by the board's link watchdog"));
        return false;
      }
    }
    if (state_ == State::kHold) {  // braked by a feed hold: the segment stays, and resumes on '~'
      hold_stopped_ = true;
      current_started_ = false;
      return false;
    }
    if (std::holds_alternative<Home>(action)) {
      const size_t a = homing_left_.front();
      if (!model.motor(axes_[a].axis->motor).homed) {
        (void)alarm(9, std::string(1, kLetters[a]) + ": homing found no switch");
        return false;
      }
      homing_left_.erase(homing_left_.begin());
      if (!homing_left_.empty()) {
        if (SessionResult<Done> next = home_next(); !next) return next.error();
        return false;
      }
      resync();
      if (SessionResult<Done> limits = send_soft_limits(); !limits) return limits.error();
      return true;
    }
    return true;
  }
  if (std::holds_alternative<Dwell>(action)) return Clock::now() >= dwell_until_;
  if (std::holds_alternative<Pause>(action)) return false;  // resumed by '~'
  if (std::holds_alternative<End>(action)) interpreter_.program_end();
  return true;
}

SessionResult<Done> FrontEnd::send_soft_limits() {
  if (session_.firmware() != Firmware::kV2) return Done{};
  for (const GrblAxis& g : axes_) {
    if (!g.axis || !g.axis->limit_min || !session_.model().motor(g.axis->motor).homed) continue;
    SoftLimits limits{g.axis->motor, 0, 0, 0, 0};
    if (soft_limits_) {
      const Axis& axis = *g.axis;
      int64_t low = axis.to_board_position(*axis.limit_min).steps;
      int64_t high = axis.to_board_position(*axis.limit_min + g.max_travel).steps;
      if (low > high) std::swap(low, high);
      limits = SoftLimits{axis.motor, low < 0 ? 1u : 0u, static_cast<uint32_t>(std::llabs(low)), high < 0 ? 1u : 0u,
                          static_cast<uint32_t>(std::llabs(high))};
    }
    SessionResult<BoardFrame> sent = session_.execute(limits);
    if (!sent && (sent.error().kind == SessionError::Kind::kLink || sent.error().kind == SessionError::Kind::kNoReply)) {
      return sent.error();
    }
  }
  return Done{};
}

// ---- reports -------------------------------------------------------------------------------

SessionResult<Done> FrontEnd::status_report() {
  // Positions of moving motors are asked for: events only say where a motion ended.
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (!moving(session_.model().motor(m))) continue;
    if (SessionResult<BoardFrame> status = session_.execute(StatusQuery{m}); !status) return status.error();
  }
  const double unit = report_inches_ ? kMmPerInch : 1.0;
  const int decimals = report_inches_ ? 4 : 3;
  const Vec3 wco = interpreter_.work_offset();
  std::string r = "<";
  r += state_name(state_);
  if (state_ == State::kHold) r += hold_stopped_ ? ":0" : ":1";
  r += report_mpos_ ? "|MPos:" : "|WPos:";
  double feed_sq = 0;
  for (size_t a = 0; a < kAxisCount; ++a) {
    const double pos = machine_mm(a) - (report_mpos_ ? 0 : wco[a]);
    r += (a ? "," : "") + fmt(pos / unit, decimals);
    if (axes_[a].axis) {
      const MotorStatus& m = session_.model().motor(axes_[a].axis->motor);
      const double v = axes_[a].axis->from_board_rate(m.rate, m.microstep);
      feed_sq += v * v;
    }
  }
  if (report_buffer_) {
    r += "|Bf:" + std::to_string(kPlannerBlocks - std::min(queue_.size(), kPlannerBlocks)) + "," +
         std::to_string(kRxBufferSize);
  }
  r += "|FS:" + fmt(std::sqrt(feed_sq) * 60.0 / unit, 0) + ",0";
  std::string pins;
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (axes_[a].axis && session_.model().motor(axes_[a].axis->motor).switches != 0) pins += kLetters[a];
  }
  if (!pins.empty()) r += "|Pn:" + pins;
  // grbl sends the work offset every 10 reports, and at once when it changed.
  if (!last_wco_ || *last_wco_ != wco || reports_ % 10 == 0) {
    r += "|WCO:" + fmt(wco[0] / unit, decimals) + "," + fmt(wco[1] / unit, decimals) + "," + fmt(wco[2] / unit, decimals);
    last_wco_ = wco;
  }
  ++reports_;
  r += ">";
  send(r);
  return Done{};
}

std::string FrontEnd::settings_text() const {
  uint32_t dir_mask = 0, homing_mask = 0;
  double seek = 0, locate = 0, pull_off = 0;
  for (size_t a = 0; a < kAxisCount; ++a) {
    const std::optional<Axis>& axis = axes_[a].axis;
    if (!axis) continue;
    if (axis->invert) dir_mask |= 1u << a;
    if (axis->homing) {
      // grbl homes toward +, unless its bit in $23 is set: the switch end in the axis's sense.
      const bool toward_negative = (axis->homing->end == 0) != axis->invert;
      if (toward_negative) homing_mask |= 1u << a;
      if (seek == 0) {
        seek = axis->homing->seek_speed.value_or(0) * 60;
        locate = axis->homing->locate_speed.value_or(0) * 60;
        pull_off = axis->homing->pull_off.value_or(0);
      }
    }
  }
  std::string s;
  const auto line = [&s](int n, const std::string& v) { s += "$" + std::to_string(n) + "=" + v + "\r\n"; };
  line(0, "10");
  line(1, "255");
  line(2, "0");
  line(3, std::to_string(dir_mask));
  line(4, "0");
  line(5, "0");
  line(6, "0");
  line(10, std::to_string((report_mpos_ ? 1 : 0) | (report_buffer_ ? 2 : 0)));
  line(11, "0.000");
  line(12, fmt(interpreter_.settings().arc_tolerance_mm));
  line(13, report_inches_ ? "1" : "0");
  line(20, soft_limits_ ? "1" : "0");
  line(21, "1");
  line(22, homing_ ? "1" : "0");
  line(23, std::to_string(homing_mask));
  line(24, fmt(locate));
  line(25, fmt(seek));
  line(26, "0");
  line(27, fmt(pull_off));
  line(30, "0");
  line(31, "0");
  line(32, "0");
  for (size_t a = 0; a < kAxisCount; ++a) line(100 + static_cast<int>(a), fmt(axes_[a].axis ? axes_[a].axis->steps_per_unit() : 0));
  for (size_t a = 0; a < kAxisCount; ++a) line(110 + static_cast<int>(a), fmt(axes_[a].max_rate));
  for (size_t a = 0; a < kAxisCount; ++a) line(120 + static_cast<int>(a), fmt(axes_[a].accel));
  for (size_t a = 0; a < kAxisCount; ++a) line(130 + static_cast<int>(a), fmt(axes_[a].max_travel));
  return s;
}

void FrontEnd::setting(const std::string& c) {
  if ((state_ != State::kIdle && state_ != State::kAlarm) || current_ || !queue_.empty()) {
    error(GrblError{kIdleError, "settings change only while the machine is idle"});
    return;
  }
  const size_t eq = c.find('=');
  if (eq == std::string::npos) {
    error(GrblError{kInvalidStatement, c + ": a setting is written $N=value"});
    return;
  }
  char* end = nullptr;
  const long n = std::strtol(c.c_str() + 1, &end, 10);
  if (end != c.c_str() + eq) {
    error(GrblError{kInvalidStatement, c + ": a setting is written $N=value"});
    return;
  }
  const std::string text = c.substr(eq + 1);
  char* value_end = nullptr;
  const double v = std::strtod(text.c_str(), &value_end);
  if (text.empty() || value_end != text.c_str() + text.size()) {
    error(GrblError{kBadNumberFormat, "$" + std::to_string(n) + "=" + text + ": not a number"});
    return;
  }
  if (v < 0) {
    error(GrblError{kNegativeValue, "$" + std::to_string(n) + ": must not be negative"});
    return;
  }
  const auto axis_of = [&](long first) -> GrblAxis* {
    const auto a = static_cast<size_t>(n - first);
    return axes_[a].axis ? &axes_[a] : nullptr;
  };
  const auto absent = [&]() {
    error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": the profile has no axis " +
                                           std::string(1, kLetters[static_cast<size_t>(n % 10)])});
  };
  if (n == 10) {
    report_mpos_ = (static_cast<int>(v) & 1) != 0;
    report_buffer_ = (static_cast<int>(v) & 2) != 0;
  } else if (n == 12) {
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$12: the arc tolerance must be above 0"});
      return;
    }
    interpreter_.settings().arc_tolerance_mm = v;
  } else if (n == 13) {
    report_inches_ = v != 0;
  } else if (n == 20) {
    if (v != 0 && !homing_) {
      error(GrblError{kSoftLimitError, "soft limits need homing enabled ($22=1)"});
      return;
    }
    soft_limits_ = v != 0;
    if (SessionResult<Done> sent = send_soft_limits(); !sent) message("soft limits not sent: " + sent.error().message);
  } else if (n == 22) {
    bool can_home = false;
    for (const GrblAxis& g : axes_) can_home = can_home || (g.axis && g.axis->homing && g.axis->motor <= 2);
    if (v != 0 && !can_home) {
      error(GrblError{kSettingDisabled, "no axis of the profile homes ([axis.NAME.homing], motors 1 and 2)"});
      return;
    }
    homing_ = v != 0;
  } else if (n == 24 || n == 25 || n == 27) {
    for (GrblAxis& g : axes_) {
      if (!g.axis || !g.axis->homing) continue;
      AxisHoming& h = *g.axis->homing;
      if (n == 24) h.locate_speed = v / 60.0;
      if (n == 25) h.seek_speed = v / 60.0;
      if (n == 27) h.pull_off = v;
    }
  } else if (n >= 100 && n <= 102) {
    GrblAxis* g = axis_of(100);
    if (g == nullptr) return absent();
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": steps per mm must be above 0"});
      return;
    }
    g->axis->mm_per_rev = g->axis->steps_per_rev_out() / v;
    resync();
  } else if (n >= 110 && n <= 112) {
    GrblAxis* g = axis_of(110);
    if (g == nullptr) return absent();
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": the maximum rate must be above 0"});
      return;
    }
    g->max_rate = v;
  } else if (n >= 120 && n <= 122) {
    GrblAxis* g = axis_of(120);
    if (g == nullptr) return absent();
    g->accel = v;
  } else if (n >= 130 && n <= 132) {
    GrblAxis* g = axis_of(130);
    if (g == nullptr) return absent();
    g->max_travel = v;
    if (!g->axis->limit_min) g->axis->limit_min = 0.0;
    g->axis->limit_max = *g->axis->limit_min + v;
    if (SessionResult<Done> sent = send_soft_limits(); !sent) message("soft limits not sent: " + sent.error().message);
  } else {
    const bool known = (n >= 0 && n <= 6) || n == 11 || n == 21 || n == 23 || n == 26 || (n >= 30 && n <= 32);
    error(GrblError{kInvalidStatement, "$" + std::to_string(n) +
                                           (known ? ": fixed by the board and the profile here (docs/grbl.md)"
                                                  : ": no such setting")});
    return;
  }
  message("$" + std::to_string(n) + " changed for this hmc grbl only: the profile file is not written");
  ok();
}

std::string FrontEnd::parameters_text() const {
  std::string s;
  const double unit = report_inches_ ? kMmPerInch : 1.0;
  const int decimals = report_inches_ ? 4 : 3;
  const auto vec = [&](const Vec3& v) {
    return fmt(v[0] / unit, decimals) + "," + fmt(v[1] / unit, decimals) + "," + fmt(v[2] / unit, decimals);
  };
  for (size_t k = 0; k < 6; ++k) s += "[G" + std::to_string(54 + k) + ":" + vec(interpreter_.coord_systems()[k]) + "]\r\n";
  s += "[G28:" + vec(Vec3{}) + "]\r\n";
  s += "[G30:" + vec(Vec3{}) + "]\r\n";
  s += "[G92:" + vec(interpreter_.g92_offset()) + "]\r\n";
  s += "[TLO:" + fmt(0, decimals) + "]\r\n";
  s += "[PRB:" + vec(Vec3{}) + ":0]\r\n";
  return s;
}

}  // namespace hmc::grbl
