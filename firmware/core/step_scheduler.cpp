// StepScheduler, main-loop side: plans moves, works out the steps' times and pushes them into
// the rings the step interrupt plays (step_engine.h): cruise runs, single steps at their exact
// times, and inside a ramp segments of up to 256 steps from a few exact points each (ramp.h,
// "Ramp segments"). Everything here runs in the
// main loop except halt() and halt_all(), which may run in a switch interrupt.
#include "step_math.h"
#include "step_scheduler.h"

namespace hmc::fw {
namespace {

using hal::Ticks;
using step_engine_detail::fence;
using step_engine_detail::LaneSteps;
using step_engine_detail::load8;
using step_engine_detail::store8;

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

template <typename T>
T load(const T& x) {
  return *static_cast<const volatile T*>(&x);
}

// `read(lane, next)` over a consistent state of lane `index` (StepLane): an interrupt between
// the reads either moves the lane's next event or counts a fold, and has them read again.
template <class Read>
auto read_lane(const StepEngine& engine, uint8_t index, Read read) {
  const StepLane& lane = engine.lanes[index];
  for (;;) {
    const uint32_t folds = load(lane.folds);
    const uint32_t next = load(engine.lanes[index].next);
    fence();
    const auto out = read(lane, next);
    fence();
    if (load(lane.folds) == folds && load(engine.lanes[index].next) == next) return out;
  }
}

// A lane's steps since power-up (what a per-step counter would hold).
uint32_t total_steps(const StepEngine& engine, uint8_t index) {
  return read_lane(engine, index, [](const StepLane& lane, uint32_t) {
    return lane.total + step_engine_detail::steps_since_fold(lane);
  });
}

// A lane's position, its move's steps and what per-step counters would hold (lane_steps).
struct LaneCounts {
  int32_t position;  // 1/256 step
  uint32_t fired;
  LaneSteps steps;
};
LaneCounts counts(const StepEngine& engine, uint8_t index) {
  return read_lane(engine, index, [](const StepLane& lane, uint32_t next) {
    const LaneSteps steps = step_engine_detail::lane_steps(lane, next);
    const uint32_t moved = (steps.total - lane.total_at) *
                           static_cast<uint32_t>(static_cast<int32_t>(lane.position_step));
    const uint32_t at = static_cast<uint32_t>(lane.position_at);
    return LaneCounts{static_cast<int32_t>(at + moved), steps.total - lane.fired_from, steps};
  });
}

Ticks later(Ticks a, Ticks b) { return a > b ? a : b; }

// Segments a push may take: a split wait, the step segment, an end marker, a DIR start.
constexpr uint8_t kPushRoom = 4;

constexpr uint32_t kOverdueTicks = 48000;  // 1 ms

}  // namespace

StepScheduler::StepScheduler(hal::StepTimer& timer, hal::StepPins& pins, Ticks handover_lead)
    : timer_(timer),
      pins_(pins),
      lead_(handover_lead > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(handover_lead)),
      clamped_(0), engine_{}, motors_{} {
  for (Motor& mo : motors_) {
    mo.active = kNoSlot;
    mo.then_slot = kNoSlot;
    mo.next_slot = kNoSlot;
    mo.next_then = kNoSlot;
    mo.phase = kNoSlot;
    mo.allowed = 2 + lead_ / kMinIntervalTicks;  // for last_delta 0 (allowed_for)
  }
}

StepStatus StepScheduler::start(uint8_t motor, const MoveSpec& move) {
  return plan_and_post(motor, &move);
}

StepStatus StepScheduler::stop(uint8_t motor) { return plan_and_post(motor, nullptr); }

// Plans `move` (or a stop, when null) against what the motor's plan is doing at the handover
// step (the first step not yet pushed) and fills its ring.
StepStatus StepScheduler::plan_and_post(uint8_t motor, const MoveSpec* move) {
  if (!is_motor(motor)) return StepStatus::kBadMotor;
  if (move != nullptr) {
    const PlanStatus status = check_move(*move);
    if (status != PlanStatus::kOk) return from_plan(status);
  }
  const uint8_t index = static_cast<uint8_t>(motor - 1);
  sync(index);
  Motor& mo = motors_[index];
  const Ticks now = timer_.now();
  // A replacement not yet reached is itself replaced: plan against the active profile.
  mo.next_slot = kNoSlot;
  mo.next_then = kNoSlot;
  uint8_t free[2] = {kNoSlot, kNoSlot};
  for (uint8_t slot = 0, found = 0; slot < kSlots && found < 2; ++slot) {
    if (slot != mo.active && slot != mo.then_slot && slot != mo.next_slot) free[found++] = slot;
  }
  Profile& first = mo.slots[free[0]];
  Profile& second = mo.slots[free[1]];
  PlanStatus status = PlanStatus::kOk;

  if (mo.active == kNoSlot) {  // at rest, or the ring plays the end of a finished move
    if (move == nullptr) return StepStatus::kOk;
    status = plan_move(*move, 0, first);
    if (status == PlanStatus::kOk) {
      begin_from_rest(index, free[0], soonest_start(first));
      produce(index);
    }
    return from_plan(status);
  }

  const Profile& current = mo.slots[mo.active];
  const bool same_way = move != nullptr && move->reverse == current.spec.reverse;
  if (!same_way && current.k == 0) {  // constant rate: stop at once
    if (move != nullptr) {
      status = plan_move(*move, 0, first);
      if (status != PlanStatus::kOk) return from_plan(status);
    }
    post_halt(index, static_cast<uint8_t>(move == nullptr ? MoveEnd::kStopped : MoveEnd::kNone));
    mo.active = kNoSlot;
    mo.then_slot = kNoSlot;
    mo.dir_known = false;  // the halt may drop a DIR change not yet made
    // The halt is taken before any event after `now`: the steps so far are all there will be.
    const LaneCounts counted = counts(engine_, index);
    mo.pushed_position = counted.position;
    mo.pushed = counted.steps.total;
    // (A start's anchor counts as its last step, and may still be ahead of `now`.)
    const int32_t since_step =
        static_cast<int32_t>(static_cast<uint32_t>(now) - counted.steps.last_step);
    const int64_t last_rise = static_cast<int64_t>(now) - since_step;
    mo.last_rise = last_rise > 0 ? static_cast<Ticks>(last_rise) : 0;
    if (move != nullptr) {
      begin_from_rest(index, free[0], soonest_start(first));
      produce(index);
    }
    kick();
    return StepStatus::kOk;
  }
  if (!same_way && current.stopping) {  // already braking to rest: only what follows changes
    if (move != nullptr) status = plan_move(*move, 0, first);
    if (status == PlanStatus::kOk) mo.then_slot = move == nullptr ? kNoSlot : free[0];
    return from_plan(status);
  }

  // The handover step h: the step after the next one (the next one's time is fixed), plus the
  // steps the lead covers at the current interval; the ring never holds more than that.
  const LaneSteps counted = counts(engine_, index).steps;
  const int32_t into = static_cast<int32_t>(counted.total - mo.profile_base);
  const uint32_t last_interval = counted.last_interval;
  const uint32_t spacing = last_interval > kMinIntervalTicks ? last_interval : kMinIntervalTicks;
  uint32_t h = static_cast<uint32_t>(into > 0 ? into : 0) + 2 + lead_ / spacing;
  if (h < mo.planned) h = mo.planned;
  if (!current.endless && h > current.total_steps) {
    // The move ends before the handover: what follows starts from rest after it.
    if (move != nullptr) status = plan_move(*move, 0, first);
    if (status == PlanStatus::kOk) mo.then_slot = move == nullptr ? kNoSlot : free[0];
    return from_plan(status);
  }

  uint64_t m = 0;
  uint8_t then_slot = kNoSlot;
  if (same_way) {
    status = speed_at(current, h, *move, m);
    if (status == PlanStatus::kOk) status = plan_move(*move, m, first);
  } else {  // brake to rest, then start the reverse move (if any) from rest
    status = speed_at(current, h, current.spec, m);
    if (status == PlanStatus::kOk) status = plan_stop(current.spec, m, first);
    if (status == PlanStatus::kOk && move != nullptr) {
      status = plan_move(*move, 0, second);
      then_slot = free[1];
    }
  }
  if (status != PlanStatus::kOk) return from_plan(status);
  mo.next_slot = free[0];
  mo.next_then = then_slot;
  mo.switch_at = h;
  produce(index);
  return StepStatus::kOk;
}

// Drops the plan of a motor the interrupt halted: a plan always has its start in the ring or
// playing, so an empty ring and a lane at rest mean the halt took it. (The interrupt marks a
// lane moving before it advances `head`, so reading the ring first cannot see a false rest.)
void StepScheduler::sync(uint8_t index) {
  Motor& mo = motors_[index];
  const StepLane& lane = engine_.lanes[index];
  const uint32_t halts = load(lane.halts);
  if (halts != mo.seen_halts) {  // a halt may have dropped a DIR change: the next start sets DIR
    mo.seen_halts = halts;
    mo.dir_known = false;
  }
  if (mo.active == kNoSlot && mo.then_slot == kNoSlot) return;
  const bool empty = load8(lane.head) == lane.tail;
  fence();
  if (!empty || load8(lane.moving) != 0) return;
  mo.active = kNoSlot;
  mo.then_slot = kNoSlot;
  mo.next_slot = kNoSlot;
  mo.next_then = kNoSlot;
  mo.move_mark = false;
  const LaneCounts counted = counts(engine_, index);
  mo.pushed_position = counted.position;
  mo.pushed = counted.steps.total;
}

// Also the guard of a compare written too late to match (the interrupt delayed past its own
// cost estimate): an event overdue by kOverdueTicks has the interrupt run at once, instead of
// waiting for the counter to come round (89 s).
void StepScheduler::fill() {
  // An idle lane costs a few loads: no plan to produce from, nothing armed to watch; the clock
  // (a synchronised counter read on the board) is read only for an armed lane.
  bool have_now = false;
  uint32_t now = 0;
  for (uint8_t index = 0; index < kMotors; ++index) {
    const Motor& mo = motors_[index];
    const StepLane& lane = engine_.lanes[index];
    // A plan whose ring still reaches past its refill point, with no halt since the last look,
    // has nothing for sync() and produce() to do (they would find that out in ≈ 100 cycles).
    const bool well_ahead = mo.active != kNoSlot && load(lane.halts) == mo.seen_halts &&
                            static_cast<int32_t>(total_steps(engine_, index) - mo.refill_total) < 0;
    if (!well_ahead) {
      sync(index);
      produce(index);
    }
    if ((load8(engine_.armed) & (1u << index)) == 0) {
      if (load8(lane.head) != lane.tail) wake(index);
      continue;
    }
    if (!have_now) {
      now = static_cast<uint32_t>(timer_.now());
      have_now = true;
    }
    if (static_cast<int32_t>(now - load(engine_.lanes[index].next)) > static_cast<int32_t>(kOverdueTicks)) {
      wake(index);
    }
  }
}

uint8_t StepScheduler::space(uint8_t index) const {
  const StepLane& lane = engine_.lanes[index];
  return static_cast<uint8_t>(kRingSize - static_cast<uint8_t>(lane.tail - load8(lane.head)));
}

void StepScheduler::push(uint8_t index, const StepSegment& seg) {
  StepLane& lane = engine_.lanes[index];
  lane.ring[lane.tail & (kRingSize - 1)] = seg;
  fence();
  store8(lane.tail, static_cast<uint8_t>(lane.tail + 1));
}

// How many steps the ring may hold ahead of the interrupt: the next two (the interrupt needs
// the one after the step it makes) and the lead's worth at the current interval (its division
// done again only when the interval changed).
uint32_t StepScheduler::steps_ahead_allowed(Motor& mo) const {
  if (mo.allowed_for != mo.last_delta) {
    const uint32_t spacing = mo.last_delta > kMinIntervalTicks ? mo.last_delta : kMinIntervalTicks;
    mo.allowed = 2 + lead_ / spacing;
    mo.allowed_for = mo.last_delta;
  }
  return mo.allowed;
}

// Tops the ring up to the steps allowed ahead once it has fallen to half of them, so a cruise
// goes in as runs of many steps (a ramp, one segment a step, is held back by the ring's size).
// Leaves in refill_total the lane's step count (StepLane::total) from which it has work again.
void StepScheduler::produce(uint8_t index) {
  Motor& mo = motors_[index];
  if (mo.active == kNoSlot) return;  // no plan: nothing to produce (and no division)
  bool pushed = false;
  const uint32_t allowed = steps_ahead_allowed(mo);
  uint32_t ahead = mo.pushed - total_steps(engine_, index);
  // (allowed ≥ 2: more than allowed / 2 ahead is at least 1.)
  mo.refill_total = mo.pushed - allowed / 2;
  if (ahead > allowed / 2) return;
  while (mo.active != kNoSlot && space(index) >= kPushRoom && ahead < allowed) {
    if (mo.next_slot != kNoSlot && mo.planned >= mo.switch_at) {  // the replacement's turn
      mo.then_slot = mo.next_then;
      begin_profile(mo, mo.next_slot, mo.last_rise);
      mo.next_slot = kNoSlot;
      mo.move_mark = true;
    }
    uint32_t most = allowed - ahead;
    // A ramp segment may reach a whole lead past the steps already pushed (the ring then holds
    // up to 1.5 leads): one long segment per top-up instead of a few shorter ones.
    uint32_t ramp_most = allowed - 2 > most ? allowed - 2 : most;
    if (mo.next_slot != kNoSlot && mo.switch_at - mo.planned < most) most = mo.switch_at - mo.planned;
    if (mo.next_slot != kNoSlot && mo.switch_at - mo.planned < ramp_most) {
      ramp_most = mo.switch_at - mo.planned;
    }
    const uint32_t ramped = push_ramp_segment(index, ramp_most);
    if (ramped != 0) {
      mo.planned += ramped;
      mo.pushed += ramped;
      ahead += ramped;
      mo.pushed_position += static_cast<int32_t>(ramped) * mo.slots[mo.active].position_step;
      mo.last_event = mo.last_rise;
      mo.rise_ok_at = mo.last_rise + kStepHighTicks + kStepLowTicks;
      pushed = true;
      continue;
    }
    Ticks first = 0;
    uint32_t count = 0;
    if (!next_run(mo, most, first, count)) {
      finish(index);
      pushed = true;
      continue;
    }
    if (first < mo.rise_ok_at) {
      first = mo.rise_ok_at;
      ++clamped_;
    }
    Ticks delta = first - mo.last_event;
    if (delta > kMaxSegmentTicks) {  // a long wait: events without a step first
      const Ticks waits = (delta - 1) / kMaxSegmentTicks;
      push(index, StepSegment{kMaxSegmentTicks, static_cast<uint32_t>(waits), 0, kSegNoStep, 0, 0});
      delta -= waits * kMaxSegmentTicks;
    }
    const int16_t position_step = mo.slots[mo.active].position_step;
    const uint8_t flags = mo.move_mark ? kSegMove : uint8_t{0};
    push(index, StepSegment{static_cast<uint32_t>(delta), 1, position_step, flags, 0, 0});
    const uint32_t interval = count > 1 ? mo.cruise_interval : 0;
    if (count > 1) push(index, StepSegment{interval, count - 1, position_step, 0, 0, 0});
    mo.move_mark = false;
    mo.planned += count;
    mo.pushed += count;
    ahead += count;
    mo.pushed_position += static_cast<int32_t>(count) * position_step;
    mo.last_delta = static_cast<uint32_t>(count > 1 ? interval : (first - mo.last_rise));
    mo.last_rise = first + static_cast<Ticks>(count - 1) * interval;
    mo.last_event = mo.last_rise;
    mo.rise_ok_at = mo.last_rise + kStepHighTicks + kStepLowTicks;
    pushed = true;
  }
  mo.refill_total = mo.pushed - steps_ahead_allowed(mo) / 2;
  if (pushed && (load8(engine_.armed) & (1u << index)) == 0) wake(index);
}

// The soonest anchor for `profile` from rest, after its planning: its first step kPickupTicks or
// more after the clock (the first step's delay: the interval at constant rate; √(2/a) s from
// rest at acceleration a, enough up to kPickupAccel).
Ticks StepScheduler::soonest_start(const Profile& profile) const {
  const uint32_t first = profile.k == 0                        ? profile.spec.interval
                         : profile.spec.accel <= kPickupAccel ? kPickupTicks
                                                              : 0;
  return timer_.now() + (first < kPickupTicks ? kPickupTicks - first : 0);
}

// The first event of a move from rest: DIR when it changes, or a wait, at the anchor (`soonest`,
// or later if the last pulse needs it).
void StepScheduler::begin_from_rest(uint8_t index, uint8_t slot, Ticks soonest) {
  Motor& mo = motors_[index];
  const Profile& profile = mo.slots[slot];
  const bool reverse = profile.spec.reverse;
  const Ticks anchor =
      mo.started ? later(soonest, mo.last_rise + kStepHighTicks + kDirGuardTicks) : soonest;
  mo.started = true;
  uint8_t flags = kSegStart | kSegNoStep;
  if (!mo.dir_known || reverse != mo.dir_reverse) {
    flags = static_cast<uint8_t>(kSegStart | kSegDir | (reverse ? kSegReverse : 0));
    mo.dir_known = true;
    mo.dir_reverse = reverse;
  }
  push(index, StepSegment{static_cast<uint32_t>(anchor), 1, profile.position_step, flags, 0, 0});
  mo.last_event = anchor;
  mo.rise_ok_at = later(mo.last_rise + kStepHighTicks + kStepLowTicks, anchor + kDirGuardTicks);
  begin_profile(mo, slot, anchor);
  mo.last_delta = profile.spec.interval;
  mo.move_mark = false;
}

void StepScheduler::begin_profile(Motor& mo, uint8_t slot, Ticks anchor) {
  const Profile& profile = mo.slots[slot];
  mo.active = slot;
  mo.k = profile.k;
  mo.anchor = anchor;
  mo.last_rise = anchor;
  mo.planned = 0;
  mo.profile_base = mo.pushed;
  mo.phase = kNoSlot;
  mo.kind = PhaseKind::kCruise;
  mo.left = 0;
  mo.kappa = mo.k != 0 ? ramp_math::isqrt(mo.k) + 1 : 0;
  mo.in_phase = false;
  mo.after_ramp = false;
}

// The active profile has no step left: the motor is at rest at the ideal rest time. A move
// waiting for it starts from rest; otherwise the motion ends.
void StepScheduler::finish(uint8_t index) {
  Motor& mo = motors_[index];
  const Ticks rest = mo.kind == PhaseKind::kDown ? mo.base : mo.last_rise;
  const Profile& profile = mo.slots[mo.active];
  const MoveEnd end = profile.stopping ? MoveEnd::kStopped : MoveEnd::kCompleted;
  mo.active = kNoSlot;
  mo.next_slot = kNoSlot;  // a replacement for a step this profile never reached
  mo.next_then = kNoSlot;
  if (mo.then_slot != kNoSlot) {
    push(index, StepSegment{0, 0, 0, kSegEnd, static_cast<uint8_t>(MoveEnd::kNone), 0});
    const uint8_t slot = mo.then_slot;
    mo.then_slot = kNoSlot;
    begin_from_rest(index, slot, rest);
    return;
  }
  push(index, StepSegment{0, 0, 0, kSegEnd, static_cast<uint8_t>(end), 0});
}

// The next run of steps of the active profile: its first step's time and how many steps (at
// most `most`) follow at the cruise interval (1 outside a cruise); false at the profile's end.
bool StepScheduler::next_run(Motor& mo, uint32_t most, Ticks& first, uint32_t& count) {
  while (mo.left == 0) {
    const Profile& profile = mo.slots[mo.active];
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
    mo.x = mo.k != 0 ? mo.m / mo.k : 0;  // once a phase: the segments' length test needs it
    mo.segment_steps = kMaxRampSegmentSteps;
    mo.fits_up_to = 0;
    mo.refused_from = kMaxRampSegmentSteps + 1;
    mo.in_phase = false;
    mo.after_ramp = false;
  }
  if (mo.kind == PhaseKind::kCruise) {
    uint32_t run = most > 0 ? most : 1u;
    if (mo.cruise_interval > kMaxSegmentTicks) run = 1;  // each step needs its own wait
    if (mo.left != kEndless && run > mo.left) run = mo.left;
    if (mo.left != kEndless) mo.left -= run;
    first = mo.base;
    count = run;
    mo.base += static_cast<Ticks>(run) * mo.cruise_interval;
    return true;
  }
  if (mo.left != kEndless) --mo.left;
  count = 1;
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
    first = mo.base + q;
    ++mo.x;
  } else {
    mo.root_step = mo.root - root;
    first = mo.base - q;
    --mo.x;
  }
  mo.root = root;
  mo.rest = rest;
  mo.in_phase = true;
  mo.after_ramp = false;
  return true;
}

// X = τ + ½ (ramp.h, "Ramp segments") of the active sqrt phase is offset + √M accelerating and
// offset − √M braking, in Q16 ticks from the last step pushed: the offset, once a segment.
int64_t StepScheduler::ideal_offset_q16(const Motor& mo) const {
  const int64_t base = static_cast<int64_t>(mo.base - mo.last_rise) * 65536;
  const int64_t h = mo.g == 0 ? 0 : 65536 - static_cast<int64_t>(mo.g);
  // Up: step at floor(base + √M + h); down: base − floor(√M + h) = floor(base + 1 − h − √M).
  return mo.kind == PhaseKind::kUp ? base + h : base + 65536 - h;
}

namespace {

// X where M has the root ⌊√M⌋ = root and M − root² = rest.
int64_t ideal_q16(bool up, int64_t offset, uint32_t root, int64_t rest) {
  const int64_t sqrt_q16 = (static_cast<int64_t>(root) << 16) +
                           ramp_math::sqrt_fraction_q16(root, static_cast<uint32_t>(rest));
  return up ? offset + sqrt_q16 : offset - sqrt_q16;
}

// ⌊√M⌋ where X would be x_q16, clamped to [0, 2³¹).
uint32_t root_guess(bool up, int64_t offset, int64_t x_q16) {
  const int64_t root = (up ? x_q16 - offset : offset - x_q16) >> 16;
  return root < 0 ? 0 : (root > 0x7FFFFFFF ? 0x7FFFFFFFu : static_cast<uint32_t>(root));
}

}  // namespace

// Pushes the next steps of a sqrt phase as one ramp segment when they may be one: the longest
// power of two the bound of ramp.h allows, within `most` and the phase. Gives its steps, 0 when
// the next step goes alone (a phase's first, a replacing move's first, out of range).
uint32_t StepScheduler::push_ramp_segment(uint8_t index, uint32_t most) {
  Motor& mo = motors_[index];
  if (!mo.in_phase || mo.move_mark || mo.kind == PhaseKind::kCruise) return 0;
  // Slower steps than a segment's interval may hold go alone (not worth two points to find out).
  if (mo.last_delta >= (kMaxRampSegmentInterval >> 16)) return 0;
  uint32_t limit = most < mo.left ? most : mo.left;
  if (limit > kMaxRampSegmentSteps) limit = kMaxRampSegmentSteps;
  const bool up = mo.kind == PhaseKind::kUp;
  // The longest power of two within the limit and twice the last segment (lengths change
  // slowly along a ramp), then halved until the bound allows it.
  const uint32_t start = 2 * mo.segment_steps < limit ? 2 * mo.segment_steps : limit;
  uint32_t n = kMaxRampSegmentSteps;
  uint32_t shift = 7;  // n/2 = 2^shift
  while (n > start && n > 2) {
    n >>= 1;
    --shift;
  }
  if (n > limit) return 0;
  // Accelerating, x only grows: a length the bound allowed earlier in the phase still fits;
  // braking, x only shrinks: one it refused is refused again.
  uint64_t reach = 0;
  for (;;) {
    if (n == 2) {  // no interpolation: its points are its steps
      if (!up && mo.x < 2) return 0;
      break;
    }
    if (up) {
      if (n <= mo.fits_up_to) break;
      if (reach == 0) reach = ramp_segment_reach(mo.x);
      if (step_math::mul_u32(n * n * n, mo.kappa) <= reach) {
        mo.fits_up_to = n;
        break;
      }
    } else if (n < mo.refused_from) {
      if (mo.x >= n && ramp_segment_fits(n, mo.x - n, mo.kappa)) break;
      mo.refused_from = n;
    }
    n >>= 1;
    --shift;
  }
  // The accumulator before the segment: the interrupt's after a ramp segment, else the last
  // (exact) step's X.
  const int64_t offset = ideal_offset_q16(mo);
  int64_t a0 = mo.fraction;
  if (!mo.after_ramp) {
    a0 = ideal_q16(up, offset, mo.root, mo.rest);
    // The step rose at floor(X): the computed X (within e of it, ramp.h) can only cross that
    // tick by e.
    if (a0 < 0) a0 = 0;
    if (a0 > 65535) a0 = 65535;
  }
  const uint32_t half = n / 2;
  // Products by powers of two as shifts (a 64-bit multiply is a library call on the M0+).
  const uint64_t k_half = mo.k << shift;
  const uint64_t m_mid = up ? mo.m + k_half : mo.m - k_half;
  const uint64_t m_end = up ? mo.m + 2 * k_half : mo.m - 2 * k_half;
  // First guesses of the roots: after a segment, its quadratic carried on (within a few ticks
  // of the ideal); after an exact step, its root's change times the steps.
  uint32_t root_mid = 0;
  uint32_t root_end = 0;
  if (mo.after_ramp) {
    // a0 + k·d + k(k − 1)/2·s at k = half and n.
    const int64_t d = mo.next_interval;
    const int64_t s = mo.next_add;
    using step_math::shl;
    root_mid = root_guess(up, offset, a0 + shl(d, shift) + shl(shl(s, shift) - s, shift) / 2);
    root_end = root_guess(up, offset, a0 + shl(d, shift + 1) + shl(shl(s, shift + 1) - s, shift));
  } else {
    const uint32_t change = half * mo.root_step;
    root_mid = up ? mo.root + change : (change < mo.root ? mo.root - change : 0);
    root_end = up ? root_mid + change : (2 * change < mo.root ? mo.root - 2 * change : 0);
  }
  int64_t rest_mid = static_cast<int64_t>(m_mid - step_math::mul_u32(root_mid, root_mid));
  step_math::settle_root(m_mid, root_mid, rest_mid);
  const int64_t x_mid = ideal_q16(up, offset, root_mid, rest_mid);
  int64_t rest_end = static_cast<int64_t>(m_end - step_math::mul_u32(root_end, root_end));
  step_math::settle_root(m_end, root_end, rest_end);
  const int64_t x_end = ideal_q16(up, offset, root_end, rest_end);
  RampSegment seg{};
  int64_t a_end = 0;
  if (!fit_ramp_segment(a0, x_mid, x_end, n, seg, a_end)) return 0;
  if (mo.last_rise + static_cast<Ticks>((a0 + seg.interval) >> 16) < mo.rise_ok_at) return 0;
  push(index, StepSegment{seg.interval, n, static_cast<int16_t>(static_cast<uint16_t>(a0)),
                          kSegRamp, 0, seg.add});
  mo.m = m_end;
  mo.root_step = (up ? root_end - root_mid : root_mid - root_end) >> shift;
  mo.root = root_end;
  mo.x = up ? mo.x + n : mo.x - n;
  mo.left -= n;
  // (n − 1)·add as a shift (n = 2^(shift + 1)).
  const int64_t last =
      static_cast<int64_t>(seg.interval) + step_math::shl(seg.add, shift + 1) - seg.add;
  mo.last_delta = static_cast<uint32_t>(last >> 16);
  mo.last_rise += static_cast<Ticks>(a_end >> 16);
  mo.fraction = static_cast<uint32_t>(a_end & 0xFFFF);
  mo.next_interval = last + seg.add;
  mo.next_add = seg.add;
  mo.after_ramp = true;
  mo.segment_steps = n;
  return n;
}

// Has the motor's interrupt take its requests now: its ring (it waits, not armed), or an
// overdue event.
void StepScheduler::wake(uint8_t index) {
  store8(engine_.lanes[index].pending, 1);
  kick();
}

// Has the lanes' interrupts run now: each with a request takes it before any due event.
void StepScheduler::kick() { timer_.schedule(timer_.now()); }

// Asks the interrupt to drop the motor's ring as far as the main loop has filled it, and stop.
void StepScheduler::post_halt(uint8_t index, uint8_t end) {
  StepLane& lane = engine_.lanes[index];
  store8(lane.halt_upto, load8(lane.tail));
  fence();
  store8(lane.halt_request, static_cast<uint8_t>(0x80u | end));
  store8(lane.pending, 1);
}

void StepScheduler::halt(uint8_t motor) {
  if (!is_motor(motor)) return;
  post_halt(static_cast<uint8_t>(motor - 1), static_cast<uint8_t>(MoveEnd::kHalted));
  kick();
}

void StepScheduler::halt_all() {
  for (uint8_t index = 0; index < kMotors; ++index) {
    post_halt(index, static_cast<uint8_t>(MoveEnd::kHalted));
  }
  kick();
}

bool StepScheduler::set_position(uint8_t motor, int32_t position) {
  if (!is_motor(motor) || is_running(motor)) return false;
  StepLane& lane = engine_.lanes[motor - 1];
  // At rest the interrupt neither steps nor folds this lane.
  *static_cast<volatile uint32_t*>(&lane.total_at) = total_steps(engine_, motor - 1);
  *static_cast<volatile int32_t*>(&lane.position_at) = position;
  motors_[motor - 1].pushed_position = position;
  return true;
}

bool StepScheduler::is_running(uint8_t motor) const {
  if (!is_motor(motor)) return false;
  const StepLane& lane = engine_.lanes[motor - 1];
  if (load8(lane.head) != lane.tail) return true;
  fence();
  return load8(lane.moving) != 0;
}

int32_t StepScheduler::position(uint8_t motor) const {
  return is_motor(motor) ? counts(engine_, motor - 1).position : 0;
}

uint32_t StepScheduler::steps_done(uint8_t motor) const {
  return is_motor(motor) ? counts(engine_, motor - 1).fired : 0;
}

bool StepScheduler::target(uint8_t motor, int32_t& out) const {
  if (!is_motor(motor)) return false;
  const Motor& mo = motors_[motor - 1];
  if (!is_running(motor)) {
    out = counts(engine_, motor - 1).position;
    return true;
  }
  if (mo.active == kNoSlot) {
    out = mo.pushed_position;
    return true;
  }
  const Profile& profile = mo.slots[mo.active];
  if (profile.endless) return false;
  const uint32_t left = profile.total_steps > mo.planned ? profile.total_steps - mo.planned : 0;
  out = static_cast<int32_t>(mo.pushed_position + static_cast<int64_t>(left) * profile.position_step);
  return true;
}

uint32_t StepScheduler::interval(uint8_t motor) const {
  return is_motor(motor) ? counts(engine_, motor - 1).steps.last_interval : 0;
}

uint32_t StepScheduler::rate(uint8_t motor) const {
  const uint32_t ticks = interval(motor);
  return ticks == 0 ? 0 : static_cast<uint32_t>(kStepTicksPerSecond / ticks);
}

uint32_t StepScheduler::finished(uint8_t motor) const {
  return is_motor(motor) ? load(engine_.lanes[motor - 1].finished) : 0;
}

MoveEnd StepScheduler::last_end(uint8_t motor) const {
  return is_motor(motor) ? static_cast<MoveEnd>(load(engine_.lanes[motor - 1].end))
                         : MoveEnd::kNone;
}

uint32_t StepScheduler::clamped_edges() const { return load(clamped_); }

uint32_t StepScheduler::starved_events() const { return load(engine_.starved); }

}  // namespace hmc::fw
