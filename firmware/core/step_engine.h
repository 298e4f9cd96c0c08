// The step interrupt: one interrupt per step, everything it needs behind one pointer.
//
// The main loop (StepScheduler, step_scheduler.cpp) works out the steps' times ahead and writes
// them into a ring per motor as segments: runs at a constant interval, single steps, and ramp
// segments ({interval, add, count} in Q16.16, played with adds only; ramp.h derives how long one
// may be); the interrupt only plays the rings back: per event it compares, adds and counts. It
// never divides, never calls through a pointer, and works on the low 32 bits of the 48 MHz
// clock with signed differences (an event is at most kMaxSegmentTicks after the previous one;
// the main loop splits longer waits into events without a step).
//
// One event, one interrupt, and no pulse to time on the CPU. Each interrupt ends by working out
// the next event: its time (`next_when`, the compare it arms), the motors due then (`next_due`)
// and which of them step (`next_steps`); arming it tells the port which STEP pins rise at the
// compare. On the SAMD21 the compare's match raises them by DMA at that exact tick and sets a
// second compare to the event's time + kStepHighTicks, whose match lowers them
// (targets/samd21/step_pulses.h): the pulse is made by hardware. The next entry, when the armed
// compare alone brought it there and the main loop asked for nothing, has no pulse to make
// (`fired` does nothing on the board; on the host it raises STEP) and does the bookkeeping: DIR
// for a due DIR event, each due motor's next event (only the due ones are visited), the
// earliest event left and its masks, the compare. Any other entry (the main loop's kick: a
// halt, a refilled ring, an overdue event; the timer's overflow) first disarms the hardware's
// STEP (`disarm`) and parks the compare (`park`), takes an armed event that came meanwhile as
// made (its STEP may have risen: it is counted before a halt could drop it), then takes the
// main loop's requests, the clock as "now", and steps the motors due by then with the CPU
// (`step_high`). An event closer than the interrupt's own cost (Port::kCostTicks) is waited for
// inside the interrupt and raised by the CPU. STEP is high at least kStepHighTicks (DRV8711
// datasheet, SLVSC40, "Timing Requirements": STEP high ≥ 1.9 µs, low ≥ 1.9 µs, DIR setup and
// hold 200 ns around a STEP edge).
//
// Port (a template parameter, so the board's registers are reached directly): the SAMD21's
// Samd21StepPort (targets/samd21/step_fast_path.h) or HalStepPort (step_scheduler_isr.cpp, over
// the HAL interfaces, for the simulator and the tests). It provides:
//   static constexpr uint32_t kCostTicks;
//   static constexpr bool kArmedStepsByHardware;  // an armed compare raises STEP by itself
//   bool event_fired(const StepEngine&);         // entered by the armed compare alone
//   void ack_event();                            // then: clears the compare's flag
//   void fired(uint8_t motors, uint32_t when);   // the armed compare's STEP on `motors` at
//                                                // `when` (made by hardware, or raised here)
//   void disarm();                               // the armed compare raises no STEP from here
//   void park(uint32_t now);                     // and does nothing more: moved to `now`
//   uint32_t take_entry();                       // otherwise: clears what entered; the clock
//   void step_high(uint8_t motors, uint32_t near);  // STEP rises now (`near`: a time within
//                                                // 2^23 ticks of now); bit m−1 for motor m;
//                                                // the pulse ends ≥ kStepHighTicks later
//   uint32_t stopwatch();                        // a mark on a free-running tick count
//   void step_low(uint8_t motors, uint32_t mark);  // a pulse the CPU ends, kStepHighTicks after
//                                                // mark (nothing where hardware ends it)
//   void set_dir(uint8_t index, bool reverse);   // index 0..2
//   // The clock against the event times: ticks from now until `when`, and a wait until then.
//   // `entry` is the entry's event time and `entry_mark` the stopwatch at entry, for a port
//   // that measures the time since entry rather than reading a clock.
//   int32_t ticks_until(uint32_t when, uint32_t entry, uint32_t entry_mark);
//   void wait_until(uint32_t when, uint32_t entry, uint32_t entry_mark);
//   void arm(uint32_t when, uint8_t motors);     // the interrupt (and STEP on `motors`) at
//                                                // `when`, ≥ kCostTicks away
//
// Ring protocol (one core, no locks): the main loop writes a segment, then advances `tail`; the
// interrupt reads a segment, then advances `head`. A motor whose ring ran dry while moving waits
// (not armed) and counts a starved event; the main loop's next push re-arms it through
// `pending`. A halt empties the ring in the interrupt; segments the main loop pushes afterwards
// that do not start a move are dropped.
//
// Code placement: on the board (ARMv6-M) the per-event code goes to .ramfunc, which the linker
// script puts in RAM (no flash wait states; samd21_sections.ld); HMC_STEP_INLINE forces the
// per-event helpers into the interrupt.
#pragma once

#include <stdint.h>

#include "ramp.h"

#if defined(__ARM_ARCH_6M__)
#define HMC_STEP_RAMFUNC __attribute__((section(".ramfunc.step_engine"), noinline, noclone))
#else
#define HMC_STEP_RAMFUNC
#endif
#define HMC_STEP_INLINE __attribute__((always_inline)) inline
// The common case of a branch (a constant-rate step of a lane whose segment goes on): -Os then
// lays it out as the straight line, the rare case as the jump.
#define HMC_STEP_LIKELY(x) __builtin_expect(!!(x), 1)
#define HMC_STEP_UNLIKELY(x) __builtin_expect(!!(x), 0)

namespace hmc::fw {

// Segment flags.
inline constexpr uint8_t kSegStart = 1;    // a move from rest: `interval` is an absolute time
inline constexpr uint8_t kSegDir = 2;      // the events set DIR (to kSegReverse) and do not step
inline constexpr uint8_t kSegReverse = 4;
inline constexpr uint8_t kSegNoStep = 8;   // the events only wait
inline constexpr uint8_t kSegEnd = 16;     // the move ends here (no event): `end` says how
inline constexpr uint8_t kSegMove = 32;    // a replacing move's first steps: `fired` restarts
// A ramp segment (ramp.h, "Ramp segments"): `interval` is the first step's interval in Q16.16,
// `add` is added to it after each step, the step rises at the accumulated time's whole tick.
inline constexpr uint8_t kSegRamp = 64;

// The longest time between two events: beyond it the main loop adds events without a step, so
// a signed 32-bit difference always orders two pending times.
inline constexpr uint32_t kMaxSegmentTicks = uint32_t{1} << 30;
// A segment of this many events never ends (an endless cruise).
inline constexpr uint32_t kEndlessEvents = 0xFFFFFFFFu;
inline constexpr uint8_t kRingSize = 32;  // a power of two

struct StepSegment {
  uint32_t interval;      // ticks after the previous event (kSegStart: the first event's time)
  uint32_t count;         // events, ≥ 1 (kEndlessEvents: endless); 0 with kSegEnd
  // kSegStart, kSegMove: position change per step (1/256 step, signed). kSegRamp: the
  // accumulator's fraction after the previous step (Q0.16, its bits).
  int16_t position_step;
  uint8_t flags;
  uint8_t end;            // kSegEnd: a MoveEnd (kNone: a move follows, the motion goes on)
  int32_t add;            // kSegRamp: Q16.16 added to the interval after each step
};

// One motor's share of the interrupt (its next event's time and whether it has one are in
// StepEngine, where the interrupt looks for the earliest). Byte fields first, then words, the
// ring last: on the M0+ a byte load reaches 31 bytes past its base register, a word load 124,
// so every field the interrupt uses is one load from the lane's address.
struct StepLane {
  uint8_t flags;       // of the playing segment
  uint8_t moving;      // a move is playing (from its start segment to its end segment)
  uint8_t end;         // the last motion's MoveEnd
  uint8_t halt_request;  // written by the main loop: 0x80 | the MoveEnd to halt with, 0 none
  uint8_t halt_upto;     // the main loop's tail when it asked: the halt drops segments before it
  uint8_t head;          // written by the interrupt
  uint8_t tail;          // written by the main loop
  int16_t position_step;
  uint32_t interval;   // of the playing segment (a ramp segment's: the next step's, Q16.16)
  uint32_t left;       // events of the playing segment from `next` on (a ramp segment: 1)
  // A ramp segment's steps after `next`, its add, and the fraction of a tick `next` carries.
  uint32_t ramp_left;
  int32_t add;
  uint32_t fraction;
  uint32_t total;        // steps since power-up (wraps)
  uint32_t last_step;    // time of the last step
  uint32_t last_interval;  // between the last two steps, 0 at rest
  // A step counts only `total`: the position (1/256 step) is position_at + (total − total_at) ×
  // position_step, the current move's steps total − fired_from. A segment that changes
  // position_step folds the steps so far into position_at first and counts a fold, so the main
  // loop reads a consistent set by reading `folds` before and after (StepScheduler::counts).
  int32_t position_at;
  uint32_t total_at;
  uint32_t fired_from;
  uint32_t folds;
  uint32_t finished;       // motions ended so far
  uint32_t halts;          // halts taken (one may have dropped a DIR change)
  StepSegment ring[kRingSize];
};

// Byte fields first (a byte load reaches 31 bytes past its base on the M0+), then words.
struct StepEngine {
  uint8_t pending;     // set by the main loop: a halt or a push for a waiting motor
  // The next event, as the last interrupt left it (read first by the next one).
  uint8_t next_steps;  // the motors whose STEP rises then
  uint8_t next_due;    // the motors due then (stepping, DIR or waiting)
  uint8_t next_armed;  // the compare is armed for next_when
  // Per motor (bit i for lane i): `next[i]` is a pending event; its segment steps (not a DIR
  // change, not a wait).
  uint8_t armed;
  uint8_t stepping;
  uint32_t next_when;  // the next event's time: the compare armed, when next_armed
  uint32_t next[3];    // each lane's next event; its last event's while not armed
  uint32_t starved;    // events that found their ring empty (0 when the main loop keeps up)
  StepLane lanes[3];
};

namespace step_engine_detail {

// Forced inline: an out-of-line copy lands in flash, which the RAM code reaches through a veneer.
HMC_STEP_INLINE uint8_t load8(const uint8_t& x) { return *static_cast<const volatile uint8_t*>(&x); }
HMC_STEP_INLINE void store8(uint8_t& x, uint8_t v) { *static_cast<volatile uint8_t*>(&x) = v; }
HMC_STEP_INLINE void fence() { __atomic_signal_fence(__ATOMIC_SEQ_CST); }
// The address as a value computed at run time: the compiler then reaches the fields by small
// offsets from it instead of from a base of its choosing (a byte load reaches 31 bytes).
template <class T>
HMC_STEP_INLINE T* based(T* p) {
  __asm__("" : "+r"(p));
  return p;
}

// A segment changes the lane's position_step (see StepLane): the steps so far go into
// position_at.
HMC_STEP_INLINE void fold_position(StepLane& lane, int16_t position_step) {
  const uint32_t total = lane.total;
  const uint32_t step = static_cast<uint32_t>(static_cast<int32_t>(lane.position_step));
  const uint32_t at = static_cast<uint32_t>(lane.position_at);
  lane.position_at = static_cast<int32_t>(at + (total - lane.total_at) * step);
  lane.total_at = total;
  lane.position_step = position_step;
  ++lane.folds;
}

// A ramp segment's next step after the event at `at`: adds only (ramp.h, "Ramp segments").
HMC_STEP_INLINE void ramp_step(StepEngine& e, uint8_t i, StepLane& lane, uint32_t at) {
  const uint32_t sum = lane.fraction + lane.interval;
  e.next[i] = at + (sum >> 16);
  lane.fraction = sum & 0xFFFFu;
  lane.interval += static_cast<uint32_t>(lane.add);
  lane.left = 1;
}

// Starts playing ramp segment `seg` after the event at `at`.
HMC_STEP_INLINE void begin_ramp(StepEngine& e, uint8_t i, StepLane& lane, const StepSegment& seg,
                                uint32_t at) {
  lane.fraction = static_cast<uint16_t>(seg.position_step);
  lane.interval = seg.interval;
  lane.add = seg.add;
  lane.ramp_left = seg.count - 1;
  ramp_step(e, i, lane, at);
}

// Takes lane i's next segment, next[i] holding the last event's time. Drops what is left of a
// halted move; passes end markers. Leaves the lane armed on its next event, or not armed.
// Per segment (a ramp segment's start included): in RAM on the board.
HMC_STEP_RAMFUNC inline void load_segment(StepEngine& e, uint8_t i) {
  StepLane& lane = e.lanes[i];
  const uint8_t bit = uint8_t(1u << i);
  for (;;) {
    const uint8_t head = lane.head;
    if (head == load8(lane.tail)) {
      e.armed = uint8_t(e.armed & ~bit);
      if (lane.moving != 0) ++e.starved;
      return;
    }
    fence();
    const StepSegment& seg = lane.ring[head & (kRingSize - 1)];
    const uint8_t flags = seg.flags;
    if ((flags & kSegStart) != 0) {
      lane.moving = 1;
      fold_position(lane, seg.position_step);
      lane.fired_from = lane.total;
      e.next[i] = seg.interval;
      lane.last_step = seg.interval;
    } else if ((flags & kSegEnd) != 0) {
      if (lane.moving != 0 && seg.end != 0) {
        lane.end = seg.end;
        ++lane.finished;
        lane.last_interval = 0;
      }
      lane.moving = 0;
      fence();
      store8(lane.head, static_cast<uint8_t>(head + 1));
      continue;
    } else if (lane.moving == 0) {  // left over from a halted move
      fence();
      store8(lane.head, static_cast<uint8_t>(head + 1));
      continue;
    } else if ((flags & kSegRamp) != 0) {
      begin_ramp(e, i, lane, seg, e.next[i]);
      lane.flags = flags;
      e.armed = uint8_t(e.armed | bit);
      e.stepping = uint8_t(e.stepping | bit);
      fence();
      store8(lane.head, static_cast<uint8_t>(head + 1));
      return;
    } else {
      e.next[i] += seg.interval;
      if ((flags & kSegMove) != 0) {
        fold_position(lane, seg.position_step);
        lane.fired_from = lane.total;
      }
    }
    lane.interval = seg.interval;
    lane.left = seg.count;
    lane.ramp_left = 0;
    lane.flags = flags;
    e.armed = uint8_t(e.armed | bit);
    if ((flags & (kSegDir | kSegNoStep)) == 0) {
      e.stepping = uint8_t(e.stepping | bit);
    } else {
      e.stepping = uint8_t(e.stepping & ~bit);
    }
    fence();
    store8(lane.head, static_cast<uint8_t>(head + 1));
    return;
  }
}

// The main loop's requests: halts first, then motors waiting for their ring.
inline void take_requests(StepEngine& e) {
  for (uint8_t i = 0; i < 3; ++i) {
    StepLane& lane = e.lanes[i];
    const uint8_t bit = uint8_t(1u << i);
    const uint8_t halt = load8(lane.halt_request);
    if (halt != 0) {
      store8(lane.halt_request, 0);
      const uint8_t upto = load8(lane.halt_upto);
      if (static_cast<uint8_t>(upto - lane.head) <= kRingSize) store8(lane.head, upto);
      const uint8_t end = halt & 0x7Fu;
      if (lane.moving != 0 && end != 0) {
        lane.end = end;
        ++lane.finished;
      }
      lane.moving = 0;
      e.armed = uint8_t(e.armed & ~bit);
      lane.last_interval = 0;
      lane.ramp_left = 0;
      ++lane.halts;
    }
    if ((e.armed & bit) == 0) load_segment(e, i);
  }
}

// Lane i's due event is done (STEP raised if it steps): account for it, take the next.
HMC_STEP_INLINE void advance(StepEngine& e, uint8_t i, uint8_t bit) {
  StepLane& lane = *based(&e.lanes[i]);
  const uint32_t at = e.next[i];
  if (HMC_STEP_LIKELY((e.stepping & bit) != 0)) {
    ++lane.total;
    lane.last_interval = at - lane.last_step;
    lane.last_step = at;
  }
  if (HMC_STEP_UNLIKELY(lane.left != kEndlessEvents && --lane.left == 0)) {
    if (lane.ramp_left != 0) {  // a ramp segment's next step
      --lane.ramp_left;
      ramp_step(e, i, lane, at);
      return;
    }
    // A plain segment after a plain one: taken here, without the call; anything else (a ramp
    // segment, a start, an end, DIR, a wait, a replacing move, an empty ring) is load_segment's.
    const uint8_t head = lane.head;
    if (lane.flags == 0 && head != load8(lane.tail)) {
      fence();
      const StepSegment& seg = lane.ring[head & (kRingSize - 1)];
      if (seg.flags == 0) {
        e.next[i] = at + seg.interval;
        lane.interval = seg.interval;
        lane.left = seg.count;
        fence();
        store8(lane.head, static_cast<uint8_t>(head + 1));
        return;
      }
    }
    load_segment(e, i);
  } else {
    e.next[i] = at + lane.interval;
  }
}

// One pass of the interrupt, STEP high on `steps` since `mark`: the due motors' DIR and next
// events, the earliest event left (e.next_when, next_due, next_steps), its compare (or none),
// the end of a pulse the CPU times.
// False when that event is too close to leave for: the caller waits for it and passes again.
template <class Port>
HMC_STEP_INLINE void step_lanes(StepEngine& e, Port& port, uint8_t due) {
#pragma GCC unroll 3
  for (uint8_t i = 0; i < 3; ++i) {
    const uint8_t bit = uint8_t(1u << i);
    if ((due & bit) == 0) continue;
    const uint8_t flags = e.lanes[i].flags;
    if (HMC_STEP_UNLIKELY((flags & kSegDir) != 0)) port.set_dir(i, (flags & kSegReverse) != 0);
    advance(e, i, bit);
  }
}

template <class Port>
HMC_STEP_INLINE bool step_pass(StepEngine& e, Port& port, uint8_t due, uint8_t steps, uint32_t now,
                               uint32_t entry, uint32_t entry_mark, uint32_t mark, bool waited) {
  // The due motors' DIR and next events.
  step_lanes(e, port, due);
  // The earliest event left and the motors due then.
  int32_t best = 0x7FFFFFFF;
  uint8_t next_due = 0;
  const uint8_t armed = e.armed;
#pragma GCC unroll 3
  for (uint8_t i = 0; i < 3; ++i) {
    const uint8_t bit = uint8_t(1u << i);
    if ((armed & bit) == 0) continue;
    const int32_t d = static_cast<int32_t>(e.next[i] - now);
    if (d < best) {
      best = d;
      next_due = bit;
    } else if (d == best) {
      next_due |= bit;
    }
  }
  const uint8_t next_steps = next_due & e.stepping;
  const uint32_t when = now + static_cast<uint32_t>(best);
  e.next_when = when;
  e.next_due = next_due;
  e.next_steps = next_steps;
  // Time has passed since entry: compare what is left. The port's clock and waits count from
  // the entry (or read the clock), not from `now`, which moves on with each pass: measured from
  // `now`, a second pass found every event already due and stepped the ring empty as fast as
  // the CPU ran.
  bool leave = true;
  if (HMC_STEP_LIKELY(next_due != 0)) {
    if (HMC_STEP_LIKELY(port.ticks_until(when, entry, entry_mark) >=
                        static_cast<int32_t>(Port::kCostTicks))) {
      port.arm(when, next_steps);
      // After a wait inside, the old compare (an event this interrupt has made) may have matched
      // meanwhile: its flag would bring the next entry in early, to raise STEP for `when` at
      // once. The old value is past, so no match comes before the new one is live.
      if (HMC_STEP_UNLIKELY(waited)) port.ack_event();
      e.next_armed = 1;
    } else {
      leave = false;
    }
  } else {
    port.disarm();  // nothing armed: the compare matches again only after the counter's wrap
    e.next_armed = 0;
  }
  if (steps != 0) port.step_low(steps, mark);
  return leave;
}

// Due before the interrupt could return and come back: waits for the event step_pass left in
// the engine, raises its STEP, and makes it the next pass's.
template <class Port>
HMC_STEP_INLINE void next_waited_event(StepEngine& e, Port& port, uint32_t entry,
                                       uint32_t entry_mark, uint32_t& now, uint8_t& due,
                                       uint8_t& steps, uint32_t& mark) {
  const uint32_t when = e.next_when;
  port.wait_until(when, entry, entry_mark);
  now = when;
  due = e.next_due;
  steps = e.next_steps;
  if (steps != 0) port.step_high(steps, when);
  mark = port.stopwatch();
}

}  // namespace step_engine_detail

// The step timer's interrupt (see the top of this file).
template <class Port>
HMC_STEP_INLINE void run_step_interrupt(StepEngine& engine, Port& port) {
  using namespace step_engine_detail;
  StepEngine& e = *based(&engine);
  uint8_t due;
  uint8_t steps;
  uint32_t now;
  const bool fired = port.event_fired(e) && load8(e.pending) == 0;
  if (HMC_STEP_LIKELY(fired)) {
    steps = e.next_steps;
    now = e.next_when;
    if (steps != 0) port.fired(steps, now);  // first: on the host this raises STEP
    port.ack_event();
    due = e.next_due;
  } else {
    port.disarm();
    steps = 0;
    if (Port::kArmedStepsByHardware && e.next_armed != 0) {
      // The armed compare is moved to now (past once live: no match until the counter wraps),
      // so nothing the hardware does at it can touch a pulse this entry makes. The armed event
      // may have come before, its STEP raised by the hardware: it is taken as made (its pulse's
      // end set from now), before a halt could drop it uncounted.
      now = port.take_entry();
      port.park(now);
      if (static_cast<int32_t>(e.next_when - now) <= 0) {
        steps = e.next_steps;
        if (steps != 0) port.step_high(steps, now);
        step_lanes(e, port, e.next_due);
      }
    }
    if (load8(e.pending) != 0) {
      store8(e.pending, 0);
      take_requests(e);
    }
    // The clock after the requests: the waits and the compare count from here (read before
    // them, the time they took went uncounted and a compare could be written for a time
    // already past, to be found only by the main loop's overdue check 1 ms later).
    now = port.take_entry();
    due = 0;
#pragma GCC unroll 3
    for (uint8_t i = 0; i < 3; ++i) {
      if ((e.armed & (1u << i)) != 0 && static_cast<int32_t>(e.next[i] - now) <= 0) {
        due |= uint8_t(1u << i);
      }
    }
    const uint8_t more = due & e.stepping;
    if (more != 0) port.step_high(more, now);
    steps = uint8_t(steps | more);
    e.next_armed = 0;
  }
  // next_armed: each pass that leaves sets it (armed, or not); a fast entry's stale 1 is not read
  // before then.
  // The entry's mark: waits and the time spent count from here (the event's time plus the
  // entry's latency), so an event waited for inside comes as late after its time as one that
  // enters the interrupt.
  const uint32_t entry_mark = port.stopwatch();
  const uint32_t entry = now;
  // The fast entry's first pass is peeled off the loop: with `now`, the mark and "not waited"
  // known constants there, its values stay in registers (in the loop -Os kept them on the stack).
  if (HMC_STEP_LIKELY(fired) && HMC_STEP_LIKELY(step_pass(e, port, due, steps, entry, entry,
                                                           entry_mark, entry_mark, false))) {
    return;
  }
  bool waited = !fired;  // a slow entry may wait for the event its compare is armed for
  uint32_t mark = entry_mark;
  if (fired) {
    next_waited_event(e, port, entry, entry_mark, now, due, steps, mark);
    waited = true;
  }
  while (!step_pass(e, port, due, steps, now, entry, entry_mark, mark, waited)) {
    next_waited_event(e, port, entry, entry_mark, now, due, steps, mark);
    waited = true;
  }
}

}  // namespace hmc::fw
