// MotionRunner: a plan's actions carried out in order through a session, stages fed per motor.
#include "hmc/motion_runner.h"

#include <algorithm>
#include <cmath>

namespace hmc::motion {
namespace {

constexpr int64_t kUnitsPerStep = 256;  // the board counts positions in 1/256 step
// Returning to the plan's positions before resuming: a safe constant rate.
constexpr uint32_t kReturnDelayUs = 500;

StepperMove stage_command(const Stage& s) { return StepperMove{s.motor, s.dir, s.microstep, s.steps, s.delay_us}; }

SessionError ended_early(std::string what) {
  return SessionError{SessionError::Kind::kEnded, std::move(what), proto::Reason::kOk};
}

// A move of `motors` that ended before its end (a switch, the emergency switch): the rest of the
// plan assumed it did not.
SessionResult<Done> moves_completed(const Session& session, const std::vector<uint32_t>& motors) {
  for (const uint32_t m : motors) {
    const std::optional<MotionEnd>& end = session.model().last_end[m - 1];
    if (end && *end != MotionEnd::kCompleted) {
      return ended_early("motor " + std::to_string(m) + "'s move ended early (" + motion_end_name(*end) + ")");
    }
  }
  return Done{};
}

}  // namespace

std::array<std::optional<double>, proto::kMotorCount> planned_positions(const Plan& plan, size_t index) {
  std::array<std::optional<double>, proto::kMotorCount> at{};
  for (const MotorTrack& t : plan.tracks) at[t.motor - 1] = t.start_exact;
  for (const Action& a : plan.actions) {
    if (a.index >= index) break;
    for (size_t i = 0; i < a.homed_at.size() && i < a.motors.size(); ++i) {
      at[a.motors[i] - 1] = static_cast<double>(a.homed_at[i]);
    }
    for (const std::vector<Stage>& motor_stages : a.stages) {
      for (const Stage& s : motor_stages) {
        std::optional<double>& p = at[s.motor - 1];
        if (p) *p += (s.dir == proto::kActionForward ? 1.0 : -1.0) * static_cast<double>(s.steps);
      }
    }
  }
  return at;
}

void start_where_board_is(const Session& session, const MotionFile& file, PlanOptions& options) {
  if (session.firmware() != Firmware::kV2) return;
  for (const MotorConfig& m : file.motors) {
    options.start_position[m.motor - 1] = static_cast<double>(session.model().motor(m.motor).position) * m.microstep /
                                          static_cast<double>(kUnitsPerStep);
  }
}

MotionRunner::MotionRunner(Session& session, const Plan& plan) : session_(session), plan_(plan) {}

void MotionRunner::emit(RunEvent::Kind kind, const Action* action) {
  if (!on_event_) return;
  RunEvent e;
  e.kind = kind;
  e.action = action;
  e.total = plan_.actions.size();
  e.elapsed_s = std::chrono::duration<double>(Clock::now() - started_).count();
  const double at = action == nullptr ? 0 : (kind == RunEvent::Kind::kActionDone ? action->end_s : action->start_s);
  e.remaining_s = std::max(0.0, plan_.duration_s - at);
  on_event_(e);
}

RunReport MotionRunner::run(const RunOptions& options) {
  on_event_ = options.on_event;
  started_ = Clock::now();
  RunReport report;
  const auto fail = [&](size_t at, const SessionError& error) {
    report.stopped_at = at;
    report.error = error;
    for (std::deque<Stage>& q : queued_) q.clear();
    // An interruption or a lost link has stopped the motors already; a refusal has not.
    if (error.kind != SessionError::Kind::kInterrupted && error.kind != SessionError::Kind::kLink) {
      (void)session_.stop_all();
    }
    return report;
  };
  if ((options.from > 1 || options.resume) && options.return_to_plan) {
    if (SessionResult<Done> back = return_to(planned_positions(plan_, options.from)); !back) {
      return fail(options.from, back.error());
    }
  }
  for (const Action& action : plan_.actions) {
    if (action.index < options.from) continue;
    emit(RunEvent::Kind::kActionStarted, &action);
    if (SessionResult<Done> done = run_action(action); !done) return fail(action.index, done.error());
    ++report.completed;
    emit(RunEvent::Kind::kActionDone, &action);
  }
  // Moves that did not wait end the file too.
  if (SessionResult<Done> rest = wait_motors({1, 2, 3}); !rest) return fail(plan_.actions.size(), rest.error());
  return report;
}

SessionResult<Done> MotionRunner::run_action(const Action& action) {
  if (SessionResult<Done> fed = feed(); !fed) return fed;
  const Clock::time_point begun = Clock::now();
  // A motor still finishing a move that did not wait must rest before it is given another.
  if (action.kind == ActionKind::kMove || action.kind == ActionKind::kHome) {
    if (SessionResult<Done> rested = wait_motors(action.motors); !rested) return rested;
  }
  for (const Command& c : action.setup) {
    if (SessionResult<BoardFrame> r = session_.execute(c); !r) return r.error();
  }
  switch (action.kind) {
    case ActionKind::kMove:
      if (SessionResult<Done> started = start_stages(action.stages); !started) return started;
      if (!action.wait_for_motors) return Done{};
      if (SessionResult<Done> waited = wait_motors(action.motors); !waited) return waited;
      return moves_completed(session_, action.motors);
    case ActionKind::kHome: {
      // One motor after another: homing needs every motor at rest. After each, its soft limits.
      size_t homed = 0;
      for (const Command& c : action.commands) {
        if (SessionResult<BoardFrame> r = session_.execute(c); !r) return r.error();
        const auto* home = std::get_if<StepperMove>(&c);
        if (home == nullptr) continue;
        const uint32_t m = home->motor;
        if (SessionResult<Done> waited = wait_motors({m}); !waited) return waited;
        // The seed firmware reports nothing; ours says whether the switch was found, and where
        // homing left the motor, which the rest of the plan counts from.
        const size_t i = homed++;
        if (session_.firmware() != Firmware::kV2) continue;
        const MotorStatus& status = session_.model().motor(m);
        if (!status.homed) return ended_early("motor " + std::to_string(m) + " not homed: " + not_homed_cause(session_.model()));
        const int64_t planned = i < action.homed_at.size() ? action.homed_at[i] : 0;
        if (static_cast<int64_t>(status.position) * home->microstep != planned * kUnitsPerStep) {
          return ended_early("motor " + std::to_string(m) + " homed at " +
                             steps_text(static_cast<int64_t>(status.position) * home->microstep) + " steps of 1/" +
                             std::to_string(home->microstep) + ", where the plan has " + std::to_string(planned) +
                             ": the board's home_pull_off or home_locate_us (hmc set) moved it off the switch");
        }
      }
      return Done{};
    }
    case ActionKind::kStop:
      for (const Command& c : action.commands) {
        if (const auto* stop = std::get_if<StepperMove>(&c)) queued_[stop->motor - 1].clear();
        if (SessionResult<BoardFrame> r = session_.execute(c); !r) return r.error();
      }
      return wait_motors(action.motors);
    case ActionKind::kWait:
      if (!action.motors.empty()) return wait_motors(action.motors);
      return wait_until(begun + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(action.end_s - action.start_s)));
    case ActionKind::kServo:
    case ActionKind::kLed:
      for (size_t i = 0; i < action.commands.size(); ++i) {
        const double offset = i < action.commands_at_s.size() ? action.commands_at_s[i] - action.start_s : 0.0;
        if (offset > 0) {
          const auto when = begun + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset));
          if (SessionResult<Done> waited = wait_until(when); !waited) return waited;
        }
        if (SessionResult<BoardFrame> r = session_.execute(action.commands[i]); !r) return r.error();
      }
      return Done{};
  }
  return Done{};
}

SessionResult<Done> MotionRunner::start_stages(const std::vector<std::vector<Stage>>& stages) {
  // First stages go out in the plan's order: it timed each motor's start from it.
  for (const std::vector<Stage>& motor_stages : stages) {
    if (motor_stages.empty()) continue;
    std::deque<Stage>& q = queued_[motor_stages.front().motor - 1];
    q.assign(motor_stages.begin(), motor_stages.end());
    const Stage first = q.front();
    q.pop_front();
    if (SessionResult<BoardFrame> r = session_.execute(stage_command(first)); !r) return r.error();
  }
  return Done{};
}

SessionResult<Done> MotionRunner::feed() {
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    std::deque<Stage>& q = queued_[m - 1];
    if (q.empty() || session_.model().motor(m).state != MotorState::kIdle) continue;
    // The previous stage ended early (a limit switch, the emergency switch): the rest is void.
    const std::optional<MotionEnd>& end = session_.model().last_end[m - 1];
    if (end && *end != MotionEnd::kCompleted) {
      q.clear();
      return ended_early("motor " + std::to_string(m) + "'s move ended early (" + motion_end_name(*end) + ")");
    }
    const Stage next = q.front();
    q.pop_front();
    if (SessionResult<BoardFrame> r = session_.execute(stage_command(next)); !r) return r.error();
  }
  return Done{};
}

SessionResult<Done> MotionRunner::wait_motors(const std::vector<uint32_t>& motors) {
  feed_error_.reset();
  SessionResult<Done> waited = session_.wait([&] {
    if (SessionResult<Done> fed = feed(); !fed) {
      feed_error_ = fed.error();
      return true;
    }
    return std::all_of(motors.begin(), motors.end(), [&](uint32_t m) {
      return queued_[m - 1].empty() && session_.model().motor(m).state == MotorState::kIdle;
    });
  });
  if (feed_error_) return *feed_error_;
  return waited;
}

SessionResult<Done> MotionRunner::wait_until(Clock::time_point when) {
  feed_error_.reset();
  SessionResult<Done> waited = session_.wait([&] {
    if (SessionResult<Done> fed = feed(); !fed) {
      feed_error_ = fed.error();
      return true;
    }
    return Clock::now() >= when;
  });
  if (feed_error_) return *feed_error_;
  return waited;
}

SessionResult<Done> MotionRunner::return_to(const std::array<std::optional<double>, proto::kMotorCount>& positions) {
  if (session_.firmware() != Firmware::kV2) return Done{};  // the seed reports no positions
  if (SessionResult<Done> fresh = session_.refresh(); !fresh) return fresh;
  std::vector<uint32_t> moving;
  for (const MotorTrack& t : plan_.tracks) {
    const std::optional<double>& target = positions[t.motor - 1];
    if (!target) continue;
    // In the board's 1/256 steps, where a fraction of a step is whole: the motor goes back exactly
    // where it was, unless it was since moved by a fraction of another microstep (then nearest).
    const double units_per_step = static_cast<double>(kUnitsPerStep) / t.microstep;
    const double away = (*target * units_per_step - static_cast<double>(session_.model().motor(t.motor).position)) /
                        units_per_step;
    const int64_t delta = std::llround(away);
    if (delta == 0) continue;
    if (moving.empty()) emit(RunEvent::Kind::kReturning, nullptr);
    const StepperMove move{t.motor, delta > 0 ? proto::kActionForward : proto::kActionReverse, t.microstep,
                           static_cast<uint32_t>(delta > 0 ? delta : -delta), kReturnDelayUs};
    if (SessionResult<BoardFrame> r = session_.execute(move); !r) return r.error();
    moving.push_back(t.motor);
  }
  return wait_motors(moving);
}

}  // namespace hmc::motion
