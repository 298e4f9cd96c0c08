// StepScheduler, interrupt side: the event list, the STEP/DIR edges and the per-step math.
// Nothing in this file divides: ctest's step_interrupt_has_no_division builds this object for
// the M0+ and fails if it calls any division (or 64-bit multiply) helper.
#include "step_math.h"
#include "step_scheduler.h"

namespace hmc::fw {
namespace {

using hal::Ticks;

Ticks later(Ticks a, Ticks b) { return a > b ? a : b; }

// An event this close is not worth leaving the interrupt for: read the clock again instead.
constexpr Ticks kRereadTicks = 64;

}  // namespace

void StepScheduler::on_step_timer() {
  fence();
  Ticks now = timer_.now();
  if (load(pending_) != 0) {
    store(pending_, uint8_t{0});
    for (Motor& mo : motors_) take_requests(mo, now);
  }
  Ticks next = kNever;
  for (;;) {
    Motor* due = &motors_[0];
    next = motors_[0].event_at;
    if (motors_[1].event_at < next) {
      due = &motors_[1];
      next = due->event_at;
    }
    if (motors_[2].event_at < next) {
      due = &motors_[2];
      next = due->event_at;
    }
    if (next > now) {
      if (next - now > kRereadTicks) break;  // includes kNever
      now = timer_.now();                     // due while we worked?
      if (next > now) break;
    }
    Motor& mo = *due;
    if (mo.event == Event::kRise) {
      pins_.set_step(mo.number, true);
      // The pulse's width counts from when the pin moved, however late the interrupt ran.
      now = timer_.now();
      mo.step_high = true;
      mo.position += mo.position_step;
      ++mo.fired;
      mo.interval = static_cast<uint32_t>(next - mo.last_rise);
      mo.last_rise = next;
      mo.event = Event::kFall;
      mo.event_at = now + kStepHighTicks;
    } else if (mo.event == Event::kFall) {
      on_fall(mo);
    } else if (mo.event == Event::kStart) {
      on_start(mo);
    } else {
      mo.event_at = kNever;
    }
  }
  if (next != kNever) timer_.schedule(next);
  fence();
}

// Takes a halt, a move to start from rest or a halt-then-start. Replacements wait for their
// step (on_fall).
void StepScheduler::take_requests(Motor& mo, Ticks now) {
  const uint8_t halt = load(mo.halt_request);
  if (halt != 0) {
    store(mo.halt_request, uint8_t{0});
    halt_now(mo, static_cast<MoveEnd>(halt));
  }
  const Ask kind = load(mo.request.kind);
  if (kind != Ask::kQueue && kind != Ask::kHaltThen) return;
  fence();
  const uint8_t slot = mo.request.slot;
  store(mo.request.kind, Ask::kNone);
  if (kind == Ask::kHaltThen) halt_now(mo, MoveEnd::kNone);  // replaced, not ended
  mo.queued = slot;
  ++mo.gen;
  if (mo.profile != nullptr || mo.event == Event::kFall) return;  // starts when that ends
  if (slot == kNoSlot) {
    mo.event = Event::kNone;
    mo.event_at = kNever;
  } else {
    mo.event = Event::kStart;
    mo.event_at = later(now, mo.dir_ok_at);
  }
}

// Ends the pulse, takes a replacement due at this step, and schedules the next rising edge.
void StepScheduler::on_fall(Motor& mo) {
  pins_.set_step(mo.number, false);
  const Ticks t = timer_.now();  // the low time counts from when the pin moved
  mo.step_high = false;
  mo.rise_ok_at = t + kStepLowTicks;
  mo.dir_ok_at = t + kDirGuardTicks;
  if (mo.profile == nullptr) {  // halted while high, or a start waiting for this edge
    mo.event = mo.queued == kNoSlot ? Event::kNone : Event::kStart;
    mo.event_at = mo.queued == kNoSlot ? kNever : mo.dir_ok_at;
    return;
  }
  if (load(mo.request.kind) == Ask::kReplace) {
    fence();
    if (mo.request.at_step == mo.planned) {
      mo.queued = mo.request.then_slot;
      const uint8_t slot = mo.request.slot;
      store(mo.request.kind, Ask::kNone);
      begin_profile(mo, slot, mo.last_rise);
    }
  }
  plan_next(mo);
}

// Starts the queued move from rest: DIR first if it changes, then the first step.
void StepScheduler::on_start(Motor& mo) {
  const Ticks t = mo.event_at;
  const uint8_t slot = mo.queued;
  mo.queued = kNoSlot;
  ++mo.gen;
  if (slot == kNoSlot) {
    mo.event = Event::kNone;
    mo.event_at = kNever;
    return;
  }
  const bool reverse = mo.slots[slot].spec.reverse;
  if (!mo.dir_known || reverse != mo.dir_reverse) {
    pins_.set_dir(mo.number, reverse);
    mo.dir_known = true;
    mo.dir_reverse = reverse;
    mo.rise_ok_at = later(mo.rise_ok_at, t + kDirGuardTicks);
  }
  begin_profile(mo, slot, t);
  plan_next(mo);
}

// Stops at once; `end` is what the motion's end counts as (kNone: it does not end, a move
// replaces it).
void StepScheduler::halt_now(Motor& mo, MoveEnd end) {
  if (load(mo.request.kind) == Ask::kReplace) store(mo.request.kind, Ask::kNone);
  const bool moving = mo.profile != nullptr || mo.queued != kNoSlot;
  mo.profile = nullptr;
  mo.active = kNoSlot;
  mo.queued = kNoSlot;
  if (mo.event != Event::kFall) {
    mo.event = Event::kNone;
    mo.event_at = kNever;
  }
  if (moving && end != MoveEnd::kNone) {
    mo.end = end;
    ++mo.finished;
  }
  mo.interval = 0;
  ++mo.gen;
}

void StepScheduler::begin_profile(Motor& mo, uint8_t slot, Ticks anchor) {
  const Profile& profile = mo.slots[slot];
  mo.active = slot;
  mo.profile = &profile;
  mo.k = profile.k;
  mo.position_step = profile.position_step;
  mo.anchor = anchor;
  mo.last_rise = anchor;
  mo.fired = 0;
  mo.planned = 0;
  mo.phase = kNoSlot;
  mo.kind = PhaseKind::kCruise;
  mo.left = 0;
  ++mo.gen;
}

void StepScheduler::plan_next(Motor& mo) {
  Ticks next = 0;
  if (!next_step_time(mo, next)) {
    finish(mo);
    return;
  }
  ++mo.planned;
  if (next < mo.rise_ok_at) {
    next = mo.rise_ok_at;
    ++clamped_;
  }
  mo.event = Event::kRise;
  mo.event_at = next;
}

// The active profile has no step left: the motor is at rest (or stops at full speed at
// constant rate). A queued move starts from the ideal rest time; otherwise the motion ends.
void StepScheduler::finish(Motor& mo) {
  const Ticks rest = mo.kind == PhaseKind::kDown ? mo.base : mo.last_rise;
  const MoveEnd end = mo.profile->stopping ? MoveEnd::kStopped : MoveEnd::kCompleted;
  mo.profile = nullptr;
  mo.active = kNoSlot;
  ++mo.gen;
  if (mo.queued != kNoSlot) {
    mo.event = Event::kStart;
    mo.event_at = later(rest, mo.dir_ok_at);
    return;
  }
  mo.event = Event::kNone;
  mo.event_at = kNever;
  mo.interval = 0;
  mo.end = end;
  ++mo.finished;
}

// The per-step math: the next step's time from the active profile, or false at its end.
bool StepScheduler::next_step_time(Motor& mo, Ticks& out) {
  while (mo.left == 0) {
    const Profile& profile = *mo.profile;
    const uint8_t next = mo.phase == kNoSlot ? 0 : static_cast<uint8_t>(mo.phase + 1);
    if (next >= profile.phase_count) return false;
    const Phase& phase = profile.phases[next];
    const Ticks reference = phase.from_last_step ? mo.last_rise : mo.anchor;
    mo.phase = next;
    mo.kind = phase.kind;
    mo.left = phase.steps;
    mo.base = reference + static_cast<Ticks>(phase.offset);
    mo.cruise_interval = phase.interval;
    mo.m = phase.m;
    mo.root = phase.root;
    mo.root_step = phase.root_step;
    mo.g = phase.h == 0 ? 0 : 65536u - phase.h;
  }
  if (mo.left != kEndless) --mo.left;
  if (mo.kind == PhaseKind::kCruise) {
    out = mo.base;
    mo.base += mo.cruise_interval;
    return true;
  }
  uint32_t root = 0;
  if (mo.kind == PhaseKind::kUp) {
    mo.m += mo.k;
    root = mo.root + mo.root_step;
  } else {
    mo.m -= mo.k;
    root = mo.root_step <= mo.root ? mo.root - mo.root_step : 0;
  }
  int64_t rest = static_cast<int64_t>(mo.m) - static_cast<int64_t>(step_math::mul_u32(root, root));
  step_math::settle_root(mo.m, root, rest);
  const uint32_t q = root + ((mo.g != 0 && step_math::rounds_up(root, rest, mo.g)) ? 1u : 0u);
  if (mo.kind == PhaseKind::kUp) {
    mo.root_step = root - mo.root;
    out = mo.base + q;
  } else {
    mo.root_step = mo.root - root;
    out = mo.base - q;
  }
  mo.root = root;
  return true;
}

}  // namespace hmc::fw
