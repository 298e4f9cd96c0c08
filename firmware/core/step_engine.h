// The step interrupt: one interrupt per step, everything it needs behind one pointer.
//
// The main loop (StepScheduler, step_scheduler.cpp) computes every step's exact time ahead and
// writes it into a ring per motor as segments; the interrupt only plays the rings back: per
// event it compares, adds and counts. It never divides, never calls through a pointer, and
// works on the low 32 bits of the 48 MHz clock with signed differences (an event is at most
// kMaxSegmentTicks after the previous one; the main loop splits longer waits into events
// without a step).
//
// One event, one interrupt. An event is a STEP pulse (or a DIR change, or nothing: a wait).
// The interrupt raises STEP on every motor due at this time with one port write, computes each
// one's next event while the pulse is high, waits until the pulse has been high
// kStepHighTicks (DRV8711 datasheet, SLVSC40, "Timing Requirements": STEP high ≥ 1.9 µs, low
// ≥ 1.9 µs, DIR setup and hold 200 ns around a STEP edge), lowers STEP, and arms the compare for
// the earliest event left. "Now" is the compare value that fired (the port's entry time); what
// the interrupt has spent since comes from a free-running cycle counter (SysTick on the SAMD21:
// one load, no clock-domain synchronisation), and an event closer than the interrupt's own cost
// (Port::kCostTicks) is waited for in the interrupt instead of leaving and coming back.
//
// Port (a template parameter, so the board's registers are reached directly): the SAMD21's
// Samd21StepPort (targets/samd21/step_fast_path.h) or HalStepPort (step_scheduler_isr.cpp, over
// the HAL interfaces, for the simulator and the tests). It provides:
//   static constexpr uint32_t kCostTicks;
//   void step_high(uint8_t motors);               // bit m−1 for motor m
//   uint32_t pulse_started();                     // the counter right after step_high
//   void step_low(uint8_t motors, uint32_t since); // after the pin has been high kStepHighTicks
//   void set_dir(uint8_t index, bool reverse);    // index 0..2
//   uint32_t elapsed();                           // ticks since the interrupt's entry
//   void wait_for(uint32_t ticks);                // until `ticks` after the entry
//   void arm(uint32_t when);                      // the interrupt at `when` (≥ kCostTicks away)
//
// Ring protocol (one core, no locks): the main loop writes a segment, then advances `tail`; the
// interrupt reads a segment, then advances `head`. A motor whose ring ran dry while moving waits
// (not armed) and counts a starved event; the main loop's next push re-arms it through
// `pending`. A halt empties the ring in the interrupt; segments the main loop pushes afterwards
// that do not start a move are dropped.
#pragma once

#include <stdint.h>

#include "ramp.h"

namespace hmc::fw {

// Segment flags.
inline constexpr uint8_t kSegStart = 1;    // a move from rest: `interval` is an absolute time
inline constexpr uint8_t kSegDir = 2;      // the events set DIR (to kSegReverse) and do not step
inline constexpr uint8_t kSegReverse = 4;
inline constexpr uint8_t kSegNoStep = 8;   // the events only wait
inline constexpr uint8_t kSegEnd = 16;     // the move ends here (no event): `end` says how
inline constexpr uint8_t kSegMove = 32;    // a replacing move's first steps: `fired` restarts

// The longest time between two events: beyond it the main loop adds events without a step, so
// a signed 32-bit difference always orders two pending times.
inline constexpr uint32_t kMaxSegmentTicks = uint32_t{1} << 30;
// A segment of this many events never ends (an endless cruise).
inline constexpr uint32_t kEndlessEvents = 0xFFFFFFFFu;
inline constexpr uint8_t kRingSize = 32;  // a power of two

struct StepSegment {
  uint32_t interval;      // ticks after the previous event (kSegStart: the first event's time)
  uint32_t count;         // events, ≥ 1 (kEndlessEvents: endless); 0 with kSegEnd
  int16_t position_step;  // kSegStart: position change per step (1/256 step, signed)
  uint8_t flags;
  uint8_t end;            // kSegEnd: a MoveEnd (kNone: a move follows, the motion goes on)
};

// One motor's share of the interrupt. Fields the interrupt uses per event come first.
struct StepLane {
  uint32_t next;       // the next event's time; the last event's while not armed
  uint32_t interval;   // of the playing segment
  uint32_t left;       // events of the playing segment from `next` on
  int32_t position;    // 1/256 step
  uint32_t fired;      // steps of the current move
  int16_t position_step;
  uint8_t flags;       // of the playing segment
  uint8_t armed;       // `next` is a pending event
  uint8_t moving;      // a move is playing (from its start segment to its end segment)
  uint8_t end;         // the last motion's MoveEnd
  uint8_t halt_request;  // written by the main loop: 0x80 | the MoveEnd to halt with, 0 none
  uint8_t halt_upto;     // the main loop's tail when it asked: the halt drops segments before it
  uint8_t head;          // written by the interrupt
  uint8_t tail;          // written by the main loop
  uint32_t total;        // steps since power-up (wraps)
  uint32_t last_step;    // time of the last step
  uint32_t last_interval;  // between the last two steps, 0 at rest
  uint32_t finished;       // motions ended so far
  uint32_t halts;          // halts taken (one may have dropped a DIR change)
  StepSegment ring[kRingSize];
};

struct StepEngine {
  uint8_t pending;   // set by the main loop: a halt or a push for a waiting motor
  uint32_t starved;  // events that found their ring empty (0 when the main loop keeps up)
  StepLane lanes[3];
};

namespace step_engine_detail {

inline uint8_t load8(const uint8_t& x) { return *static_cast<const volatile uint8_t*>(&x); }
inline void store8(uint8_t& x, uint8_t v) { *static_cast<volatile uint8_t*>(&x) = v; }
inline void fence() { __atomic_signal_fence(__ATOMIC_SEQ_CST); }

// Takes the lane's next segment, `next` holding the last event's time. Drops what is left of a
// halted move; passes end markers. Leaves the lane armed on its next event, or not armed.
inline void load_segment(StepEngine& e, StepLane& lane) {
  for (;;) {
    const uint8_t head = lane.head;
    if (head == load8(lane.tail)) {
      lane.armed = 0;
      if (lane.moving != 0) ++e.starved;
      return;
    }
    fence();
    const StepSegment& seg = lane.ring[head & (kRingSize - 1)];
    const uint8_t flags = seg.flags;
    if ((flags & kSegStart) != 0) {
      lane.moving = 1;
      lane.fired = 0;
      lane.position_step = seg.position_step;
      lane.next = seg.interval;
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
    } else {
      lane.next += seg.interval;
      if ((flags & kSegMove) != 0) {
        lane.fired = 0;
        lane.position_step = seg.position_step;
      }
    }
    lane.interval = seg.interval;
    lane.left = seg.count;
    lane.flags = flags;
    lane.armed = 1;
    fence();
    store8(lane.head, static_cast<uint8_t>(head + 1));
    return;
  }
}

// The main loop's requests: halts first, then motors waiting for their ring.
inline void take_requests(StepEngine& e) {
  for (uint8_t i = 0; i < 3; ++i) {
    StepLane& lane = e.lanes[i];
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
      lane.armed = 0;
      lane.last_interval = 0;
      ++lane.halts;
    }
    if (lane.armed == 0) load_segment(e, lane);
  }
}

// The lane's due event is done (STEP raised if it steps): account for it, take the next.
inline void advance(StepEngine& e, StepLane& lane) {
  if ((lane.flags & (kSegNoStep | kSegDir)) == 0) {
    lane.position += lane.position_step;
    ++lane.fired;
    ++lane.total;
    lane.last_interval = lane.next - lane.last_step;
    lane.last_step = lane.next;
  }
  if (lane.left != kEndlessEvents && --lane.left == 0) {
    load_segment(e, lane);
  } else {
    lane.next += lane.interval;
  }
}

}  // namespace step_engine_detail

// The step timer's interrupt. `now`: the compare value that fired, or the counter when the
// main loop had the interrupt run at once.
template <class Port>
void run_step_interrupt(StepEngine& e, Port& port, uint32_t now) {
  using namespace step_engine_detail;
  const uint32_t entry = now;
  if (load8(e.pending) != 0) {
    store8(e.pending, 0);
    take_requests(e);
  }
  for (;;) {
    // The motors due now: which step, which only change DIR or wait.
    uint8_t due = 0;
    uint8_t steps = 0;
#pragma GCC unroll 3  // constant offsets instead of a multiply per motor
    for (uint8_t i = 0; i < 3; ++i) {
      const StepLane& lane = e.lanes[i];
      if (lane.armed == 0 || static_cast<int32_t>(lane.next - now) > 0) continue;
      due |= uint8_t(1u << i);
      if ((lane.flags & (kSegDir | kSegNoStep)) == 0) {
        steps |= uint8_t(1u << i);
      } else if ((lane.flags & kSegDir) != 0) {
        port.set_dir(i, (lane.flags & kSegReverse) != 0);
      }
    }
    uint32_t since = 0;
    if (steps != 0) {
      port.step_high(steps);
      since = port.pulse_started();
    }
    // While the pulse is high: each due motor's next event, and the earliest event left.
    int32_t best = 0x7FFFFFFF;
    uint32_t when = 0;
#pragma GCC unroll 3
    for (uint8_t i = 0; i < 3; ++i) {
      StepLane& lane = e.lanes[i];
      if ((due & (1u << i)) != 0) advance(e, lane);
      if (lane.armed == 0) continue;
      const int32_t d = static_cast<int32_t>(lane.next - now);
      if (d < best) {
        best = d;
        when = lane.next;
      }
    }
    if (steps != 0) port.step_low(steps, since);
    if (best == 0x7FFFFFFF) return;  // nothing armed
    // Time has passed since entry (the pulses above, at least): compare what is left. Both
    // the port's clock and its waits count from the entry, not from `now`, which moves on
    // with each pass: measured from `now`, a second pass found every event already due and
    // stepped the ring empty as fast as the CPU ran.
    const int32_t after_entry = static_cast<int32_t>(when - entry);
    if (after_entry - static_cast<int32_t>(port.elapsed()) >= static_cast<int32_t>(Port::kCostTicks)) {
      port.arm(when);
      return;
    }
    // Due before the interrupt could return and come back: wait for it here.
    if (best > 0) {
      if (after_entry > 0) port.wait_for(static_cast<uint32_t>(after_entry));
      now = when;
    }
  }
}

}  // namespace hmc::fw
