// StepScheduler, main-loop side: plans moves and hands them to the interrupt through each
// motor's request. Planning divides; the interrupt side (step_scheduler_isr.cpp) never does.
#include "step_scheduler.h"

namespace hmc::fw {
namespace {

using hal::Ticks;

StepStatus from_plan(PlanStatus status) {
  switch (status) {
    case PlanStatus::kOk:
      return StepStatus::kOk;
    case PlanStatus::kBadMicrostep:
      return StepStatus::kBadMicrostep;
    case PlanStatus::kIntervalShort:
      return StepStatus::kIntervalShort;
    case PlanStatus::kBadAccel:
      return StepStatus::kBadAccel;
    case PlanStatus::kRampTooLong:
      return StepStatus::kRampTooLong;
  }
  return StepStatus::kRampTooLong;
}

bool is_motor(uint8_t motor) { return motor >= 1 && motor <= StepScheduler::kMotors; }

// Tries to replace with a retry budget; each failed handover doubles the lead.
constexpr int kAttempts = 8;

}  // namespace

StepScheduler::StepScheduler(hal::StepTimer& timer, hal::StepPins& pins, Ticks handover_lead)
    : timer_(timer), pins_(pins), lead_(handover_lead), clamped_(0), pending_(0), motors_{} {
  uint8_t number = 0;
  for (Motor& mo : motors_) {
    mo.number = ++number;
    mo.profile = nullptr;
    mo.active = kNoSlot;
    mo.queued = kNoSlot;
    mo.phase = kNoSlot;
    mo.request.kind = Ask::kNone;
    mo.request.slot = kNoSlot;
    mo.request.then_slot = kNoSlot;
    mo.event = Event::kNone;
    mo.event_at = kNever;
  }
}

StepStatus StepScheduler::start(uint8_t motor, const MoveSpec& move) {
  return plan_and_post(motor, &move);
}

StepStatus StepScheduler::stop(uint8_t motor) { return plan_and_post(motor, nullptr); }

// Plans `move` (or a stop, when null) against what the motor is doing and posts it. The
// request slot is withdrawn first, so the interrupt's state can change only by itself: by
// firing steps, ending the move or a halt, which `gen` reveals.
StepStatus StepScheduler::plan_and_post(uint8_t motor, const MoveSpec* move) {
  if (!is_motor(motor)) return StepStatus::kBadMotor;
  if (move != nullptr) {
    const PlanStatus status = check_move(*move);
    if (status != PlanStatus::kOk) return from_plan(status);
  }
  Motor& mo = motors_[motor - 1];
  Ticks lead = lead_;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    store(mo.request.kind, Ask::kNone);
    fence();
    const uint32_t gen = load(mo.gen);
    const uint8_t active = load(mo.active);
    const uint8_t queued = load(mo.queued);
    const uint32_t planned = load(mo.planned);
    const uint32_t last_interval = load(mo.interval);
    if (load(mo.gen) != gen) continue;

    uint8_t free[2] = {kNoSlot, kNoSlot};
    for (uint8_t slot = 0, found = 0; slot < kSlots && found < 2; ++slot) {
      if (slot != active && slot != queued) free[found++] = slot;
    }
    Profile& first = mo.slots[free[0]];
    Profile& second = mo.slots[free[1]];

    if (active == kNoSlot) {  // at rest, or a start not yet taken
      if (move == nullptr) {
        if (queued != kNoSlot) post(mo, Ask::kQueue, kNoSlot);
        return StepStatus::kOk;
      }
      const PlanStatus status = plan_move(*move, 0, first);
      if (status == PlanStatus::kOk) post(mo, Ask::kQueue, free[0]);
      return from_plan(status);
    }

    const Profile& current = mo.slots[active];
    const bool same_way = move != nullptr && move->reverse == current.spec.reverse;
    if (!same_way && current.k == 0) {  // constant rate: stop at once
      if (move == nullptr) {
        post_halt(mo, MoveEnd::kStopped);
        kick();
        return StepStatus::kOk;
      }
      const PlanStatus status = plan_move(*move, 0, first);
      if (status == PlanStatus::kOk) post(mo, Ask::kHaltThen, free[0]);
      return from_plan(status);
    }
    if (!same_way && current.stopping) {  // already braking to rest: only what follows changes
      PlanStatus status = PlanStatus::kOk;
      if (move != nullptr) status = plan_move(*move, 0, first);
      if (status == PlanStatus::kOk) post(mo, Ask::kQueue, move == nullptr ? kNoSlot : free[0]);
      return from_plan(status);
    }

    const Ticks spacing = last_interval > kMinIntervalTicks ? last_interval : kMinIntervalTicks;
    const uint32_t ahead = lead == 0 ? 0 : static_cast<uint32_t>(lead / spacing) + 1;
    const uint32_t at_step = planned + ahead;
    if (!current.endless && at_step > current.total_steps) {
      // The move ends before the handover: what follows starts from rest after it.
      PlanStatus status = PlanStatus::kOk;
      if (move != nullptr) status = plan_move(*move, 0, first);
      if (status == PlanStatus::kOk) post(mo, Ask::kQueue, move == nullptr ? kNoSlot : free[0]);
      return from_plan(status);
    }

    uint64_t m = 0;
    PlanStatus status = PlanStatus::kOk;
    uint8_t then_slot = kNoSlot;
    if (same_way) {
      status = speed_at(current, at_step, *move, m);
      if (status == PlanStatus::kOk) status = plan_move(*move, m, first);
    } else {  // brake to rest, then start the reverse move (if any) from rest
      status = speed_at(current, at_step, current.spec, m);
      if (status == PlanStatus::kOk) status = plan_stop(current.spec, m, first);
      if (status == PlanStatus::kOk && move != nullptr) {
        status = plan_move(*move, 0, second);
        then_slot = free[1];
      }
    }
    if (status != PlanStatus::kOk) return from_plan(status);
    if (post_replace(mo, gen, at_step, free[0], then_slot)) return StepStatus::kOk;
    lead = lead * 2 + 4 * kMinIntervalTicks;
  }
  return StepStatus::kBusy;
}

// Posts a replacement for step `at_step`. False when the interrupt had already fixed the time
// of the step after it (or the move changed) before the request was visible: the request is
// then withdrawn and the caller plans again.
bool StepScheduler::post_replace(Motor& mo, uint32_t gen, uint32_t at_step, uint8_t slot,
                                 uint8_t then_slot) {
  mo.request.slot = slot;
  mo.request.then_slot = then_slot;
  mo.request.at_step = at_step;
  fence();
  store(mo.request.kind, Ask::kReplace);
  fence();
  const uint32_t planned = load(mo.planned);
  const uint32_t now_gen = load(mo.gen);
  if (load(mo.request.kind) != Ask::kReplace) return true;  // taken (or cleared by a halt)
  if (planned <= at_step && now_gen == gen) return true;    // taken when that step falls
  store(mo.request.kind, Ask::kNone);
  return false;
}

void StepScheduler::post(Motor& mo, Ask kind, uint8_t slot) {
  mo.request.slot = slot;
  fence();
  store(mo.request.kind, kind);
  store(pending_, uint8_t{1});
  kick();
}

// Has the interrupt run now: it takes requests before any due edge.
void StepScheduler::kick() { timer_.schedule(timer_.now()); }

// Withdraws any request (a start not yet taken does not happen) and asks for a halt.
void StepScheduler::post_halt(Motor& mo, MoveEnd end) {
  store(mo.request.kind, Ask::kNone);
  store(mo.halt_request, static_cast<uint8_t>(end));
  store(pending_, uint8_t{1});
}

void StepScheduler::halt(uint8_t motor) {
  if (!is_motor(motor)) return;
  post_halt(motors_[motor - 1], MoveEnd::kHalted);
  kick();
}

void StepScheduler::halt_all() {
  for (Motor& mo : motors_) post_halt(mo, MoveEnd::kHalted);
  kick();
}

bool StepScheduler::set_position(uint8_t motor, int32_t position) {
  if (!is_motor(motor) || is_running(motor)) return false;
  store(motors_[motor - 1].position, position);
  return true;
}

bool StepScheduler::is_running(uint8_t motor) const {
  if (!is_motor(motor)) return false;
  const Motor& mo = motors_[motor - 1];
  const Ask kind = load(mo.request.kind);
  if (kind == Ask::kHaltThen || (kind == Ask::kQueue && mo.request.slot != kNoSlot)) return true;
  return load(mo.active) != kNoSlot || load(mo.queued) != kNoSlot;
}

int32_t StepScheduler::position(uint8_t motor) const {
  return is_motor(motor) ? load(motors_[motor - 1].position) : 0;
}

uint32_t StepScheduler::steps_done(uint8_t motor) const {
  return is_motor(motor) ? load(motors_[motor - 1].fired) : 0;
}

bool StepScheduler::target(uint8_t motor, int32_t& out) const {
  if (!is_motor(motor)) return false;
  const Motor& mo = motors_[motor - 1];
  // The interrupt may change the move between the reads; gen tells, and the read is retried.
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    const uint32_t gen = load(mo.gen);
    fence();
    const uint8_t active = load(mo.active);
    const int32_t position = load(mo.position);
    const uint32_t fired = load(mo.fired);
    fence();
    if (load(mo.gen) != gen) continue;
    if (active == kNoSlot) {
      out = position;
      return true;
    }
    const Profile& profile = mo.slots[active];
    if (profile.endless) return false;
    const uint32_t left = profile.total_steps > fired ? profile.total_steps - fired : 0;
    out = static_cast<int32_t>(position + static_cast<int64_t>(left) * profile.position_step);
    return true;
  }
  return false;
}

uint32_t StepScheduler::interval(uint8_t motor) const {
  return is_motor(motor) ? load(motors_[motor - 1].interval) : 0;
}

uint32_t StepScheduler::rate(uint8_t motor) const {
  const uint32_t ticks = interval(motor);
  return ticks == 0 ? 0 : static_cast<uint32_t>(kStepTicksPerSecond / ticks);
}

uint32_t StepScheduler::finished(uint8_t motor) const {
  return is_motor(motor) ? load(motors_[motor - 1].finished) : 0;
}

MoveEnd StepScheduler::last_end(uint8_t motor) const {
  return is_motor(motor) ? load(motors_[motor - 1].end) : MoveEnd::kNone;
}

uint32_t StepScheduler::clamped_edges() const { return load(clamped_); }

}  // namespace hmc::fw
