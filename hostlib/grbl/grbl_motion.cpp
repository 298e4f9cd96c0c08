// The grbl front end's motion (grbl.h): queued moves started on the board, each axis following
// its share of one speed profile, homing axis by axis, the soft limits sent to the board.
#include "grbl_shared.h"

#include <algorithm>
#include <cmath>

#include "hmc/axis_moves.h"

namespace hmc::grbl {

using namespace detail;

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
  // grbl owns the board while it runs: a pull-off or slow re-approach the profile leaves out is
  // set to 0 (none), not left as an earlier session set it.
  const HomingSetup setup =
      homing_setup(axis, StepperMove{axis.motor, proto::kActionHome, 0, 0, 0}, UnsetHoming::kNone);
  std::vector<Command> commands(setup.settings.begin(), setup.settings.end());
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

}  // namespace hmc::grbl
