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
// One compare per motor, one interrupt per event, and no pulse to time on the CPU. Each lane
// (motor) has its own timer compare and interrupt (on the SAMD21: TC4 for motor 1, TCC1 for
// motor 2, TCC2 for motor 3, targets/samd21/step_timer.h); the lanes' interrupts share one
// priority, so none preempts another, and each touches its own lane's hardware. Each interrupt
// ends by arming its lane's next event: the compare at its time, telling the port whether STEP
// rises then. On the SAMD21 the compare's match raises the lane's STEP by DMA at that exact tick
// and sets the lane's second compare to the event's time + kStepHighTicks, whose match lowers
// it (targets/samd21/step_pulses.h): the pulse is made by hardware, and no other motor's event
// can delay it. The next entry, when the armed compare brought it there and the main loop asked
// nothing of the lane, has no pulse to make (`fired` does nothing on the board; on the host it
// raises STEP) and does the bookkeeping: DIR for a due DIR event, the lane's next event, the
// compare. An event beyond the compare's counter's reach (Port::kReachTicks: TCC2 counts 16
// bits) is reached through relays: compares on the way that step nothing. Any other entry with
// a request from the main loop (a halt, a refilled ring, an overdue event) first disarms the
// lane's STEP (`disarm`) and parks its compare (`park`), takes an armed event that came
// meanwhile as made (its STEP may have risen: it is counted before a halt could drop it), then
// takes the requests and the clock as "now". An entry with neither (another lane's kick, a
// parked compare come round with its counter) only clears its flag. An event closer than the
// interrupt's own cost (Port::kCostTicks) is waited for inside the interrupt and raised by the
// CPU (`step_high`). STEP is high at least kStepHighTicks (DRV8711 datasheet, SLVSC40, "Timing
// Requirements": STEP high ≥ 1.9 µs, low ≥ 1.9 µs, DIR setup and hold 200 ns around a STEP
// edge).
//
// Port (a template parameter, so the board's registers are reached directly): the SAMD21's
// Samd21StepPort (targets/samd21/step_fast_path.h) or HalStepPort (step_scheduler_isr.cpp, over
// the HAL interfaces, for the simulator and the tests). It provides:
//   static constexpr uint8_t kLane;              // the lane whose interrupt this is: 0..2
//   static constexpr uint32_t kCostTicks;
//   static constexpr uint32_t kReachTicks;      // an event at most this far ahead is armed
//                                                // directly (≥ kMaxSegmentTicks: no relays)
//   static constexpr bool kArmedStepsByHardware;  // an armed compare raises STEP by itself
//   bool event_fired(const StepEngine&);         // the lane's compare has matched
//   void ack_event();                            // clears the compare's flag
//   void fired(uint32_t when);                   // the armed compare's STEP at `when` (made
//                                                // by hardware, or raised here)
//   void disarm();                               // the armed compare raises no STEP from here
//   void park(uint32_t now);                     // and does nothing more: moved to `now`
//   uint32_t take_entry();                       // clears the compare's flag; the clock
//   void step_high(uint32_t near);               // STEP rises now (`near`: a time within 2^23
//                                                // ticks of now); the pulse ends
//                                                // ≥ kStepHighTicks later
//   uint32_t stopwatch();                        // a mark on a free-running tick count
//   void step_low(uint32_t mark);                // a pulse the CPU ends, kStepHighTicks after
//                                                // mark (nothing where hardware ends it)
//   void set_dir(uint8_t index, bool reverse);   // index 0..2
//   // The clock against the event times: ticks from now until `when`, and a wait until then.
//   // `entry` is the entry's event time and `entry_mark` the stopwatch at entry, for a port
//   // that measures the time since entry rather than reading a clock.
//   int32_t ticks_until(uint32_t when, uint32_t entry, uint32_t entry_mark);
//   void wait_until(uint32_t when, uint32_t entry, uint32_t entry_mark);
//   void arm(uint32_t when, bool step);          // the compare (and STEP, if `step`) at
//                                                // `when`, ≥ kCostTicks away
//   void rearm(uint32_t when);                   // the same, STEP as the event just made
//
// Ring protocol (one core, no locks): the main loop writes a segment, then advances `tail`; the
// interrupt reads a segment, then advances `head`. A motor whose ring ran dry while moving waits
// (not armed) and counts a starved event; the main loop's next push re-arms it through the
// lane's `pending`. A halt empties the ring in the interrupt; segments the main loop pushes
// afterwards that do not start a move are dropped.
//
// Code placement: on the board (ARMv6-M) the per-event code goes to .ramfunc, which the linker
// script puts in RAM (no flash wait states; samd21_sections.ld); HMC_STEP_INLINE forces the
// per-event helpers into the interrupt.
#pragma once

#include <stddef.h>
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
inline constexpr uint8_t kRingSize = 32;  // a power of two
// The express entry (run_lane_express) takes events less than this far apart (2^20 ticks, 22 ms):
// well within the reach of the SysTick-based clock the board's port measures them with.
inline constexpr uint32_t kExpressBits = 20;
inline constexpr uint32_t kExpressTicks = uint32_t{1} << kExpressBits;

struct StepSegment {
  uint32_t interval;      // ticks after the previous event (kSegStart: the first event's time)
  uint32_t count;         // events, ≥ 1; 0 with kSegEnd (an endless cruise is pushed in runs)
  // kSegStart, kSegMove: position change per step (1/256 step, signed). kSegRamp: the
  // accumulator's fraction after the previous step (Q0.16, its bits).
  int16_t position_step;
  uint8_t flags;
  uint8_t end;            // kSegEnd: a MoveEnd (kNone: a move follows, the motion goes on)
  int32_t add;            // kSegRamp: Q16.16 added to the interval after each step
};

// One motor's share of the interrupt (whether its next event steps, and whether it has one, are
// StepEngine's masks). Byte fields first, then words, the ring last: on the M0+ a byte load
// reaches 31 bytes past its base register, a word load 124, so every field the interrupt uses
// is one load from the lane's address.
struct StepLane {
  // The first word is what the express entry checks, in one load (kExpressPlain, kExpressRamp).
  uint8_t compare;       // what the lane's compare is armed for: kCompareIdle, Event or Relay
  uint8_t flags;       // of the playing segment
  uint8_t pending;       // set by the main loop (a halt, a push for a waiting lane), cleared here
  uint8_t halt_request;  // written by the main loop: 0x80 | the MoveEnd to halt with, 0 none
  uint8_t moving;      // a move is playing (from its start segment to its end segment)
  uint8_t end;         // the last motion's MoveEnd
  uint8_t halt_upto;     // the main loop's tail when it asked: the halt drops segments before it
  uint8_t head;          // written by the interrupt
  uint8_t tail;          // written by the main loop
  int16_t position_step;
  uint32_t next;       // the lane's next event; its last event's while not armed
  uint32_t interval;   // of the playing segment (a ramp segment's: the next step's, Q16.16)
  uint32_t left;       // events of the playing segment from `next` on (a ramp segment: 1)
  // A ramp segment's steps after `next`, its add, and the fraction of a tick `next` carries.
  uint32_t ramp_left;
  int32_t add;
  uint32_t fraction;
  uint32_t relay_at;   // kCompareRelay: the relay's time
  // An event counts only `left` (and a ramp step `ramp_left`). The steps since power-up, the
  // last step's time and the interval before it are derived where they are read (lane_steps):
  // count − left − ramp_left steps since the last fold, and these three hold the values at the
  // fold. load_segment and a halt fold (fold_steps: count 0); a plain segment after a plain
  // one, taken in advance(), adds its events to `count` instead.
  uint32_t count;          // events since the last fold, the playing segment's included
  uint32_t total;          // steps since power-up at the last fold (wraps)
  uint32_t last_step;      // time of the last step then
  uint32_t last_interval;  // between the last two steps then, 0 at rest
  // The position (1/256 step) is position_at + (total − total_at) × position_step, the current
  // move's steps total − fired_from (total as lane_steps derives it). A segment that changes
  // position_step folds the steps so far into position_at first.
  int32_t position_at;
  uint32_t total_at;
  uint32_t fired_from;
  // Folds so far: the main loop reads a consistent set by reading `folds` and the lane's next
  // event (which every event moves) before and after (StepScheduler's lane_snapshot).
  uint32_t folds;
  uint32_t finished;       // motions ended so far
  uint32_t halts;          // halts taken (one may have dropped a DIR change)
  StepSegment ring[kRingSize];
};

// What a lane's compare is armed for (StepLane::compare).
inline constexpr uint8_t kCompareIdle = 0;   // nothing: parked, raising nothing
inline constexpr uint8_t kCompareEvent = 1;  // the lane's next event, StepLane::next
inline constexpr uint8_t kCompareRelay = 2;  // relay_at, on the way to a `next` beyond its reach

// A lane's first word (compare, flags, pending, halt_request, little-endian) when the express
// entry may take its event: a plain run's or a ramp segment's, armed, nothing asked. (The plain
// one is a compare with an immediate on the M0+.)
inline constexpr uint32_t kExpressPlain = kCompareEvent;
inline constexpr uint32_t kExpressRamp = kExpressPlain | uint32_t{kSegRamp} << 8;
static_assert(offsetof(StepLane, compare) == 0 && offsetof(StepLane, flags) == 1 &&
                  offsetof(StepLane, pending) == 2 && offsetof(StepLane, halt_request) == 3,
              "the express entry reads these four bytes as one word");

// Byte fields first (a byte load reaches 31 bytes past its base on the M0+), then words. The
// lanes' interrupts share one priority (none preempts another), so the masks below, written by
// each for its own bit, need no lock.
struct StepEngine {
  // Per motor (bit i for lane i): the lane's `next` is a pending event; its segment steps (not
  // a DIR change, not a wait).
  uint8_t armed;
  uint8_t stepping;
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
}

// A ramp segment's state one event back: the interval and fraction before the step that made
// the event, and that event's ticks after the one before it (ramp_step undone; the fraction
// before is the one whose sum with the interval leaves the fraction after).
HMC_STEP_INLINE uint32_t ramp_back(uint32_t& fraction, uint32_t& interval, uint32_t add) {
  interval -= add;
  fraction = (fraction - interval) & 0xFFFFu;
  return (fraction + interval) >> 16;
}

// What per-step counters would hold (StepLane): steps since power-up, the last step's time and
// the interval between the last two steps.
struct LaneSteps {
  uint32_t total;
  uint32_t last_step;
  uint32_t last_interval;
};

// Steps since the last fold.
HMC_STEP_INLINE uint32_t steps_since_fold(const StepLane& lane) {
  if ((lane.flags & (kSegDir | kSegNoStep)) != 0) return 0;
  return lane.count - lane.left - lane.ramp_left;
}

// Derives them from the lane and its next event `next` (the last event's time once the segment
// has played out: left 0).
HMC_STEP_INLINE LaneSteps lane_steps(const StepLane& lane, uint32_t next) {
  LaneSteps s{lane.total, lane.last_step, lane.last_interval};
  const uint32_t done = steps_since_fold(lane);
  if (done == 0) return s;
  uint32_t last = next;
  uint32_t interval = lane.interval;
  if ((lane.flags & kSegRamp) != 0) {
    uint32_t fraction = lane.fraction;
    const uint32_t add = static_cast<uint32_t>(lane.add);
    if (lane.left != 0) last -= ramp_back(fraction, interval, add);
    interval = ramp_back(fraction, interval, add);
  } else if (lane.left != 0) {
    last -= interval;
  }
  s.total += done;
  s.last_step = last;
  // The first step since the fold follows the last one before it (after a wait, a DIR change,
  // the start); a later one follows a step of the same segment (or of the plain one before).
  s.last_interval = done == 1 ? last - lane.last_step : interval;
  return s;
}

// The playing segment's steps go into the lane's counts (`next` as lane_steps takes it).
HMC_STEP_INLINE void fold_steps(StepLane& lane, uint32_t next) {
  const LaneSteps s = lane_steps(lane, next);
  lane.total = s.total;
  lane.last_step = s.last_step;
  lane.last_interval = s.last_interval;
  lane.count = 0;
  lane.left = 0;
  lane.ramp_left = 0;
  ++lane.folds;
}

// A ramp segment's next step after the event at `at`: adds only (ramp.h, "Ramp segments").
HMC_STEP_INLINE void ramp_step(StepLane& lane, uint32_t at) {
  const uint32_t sum = lane.fraction + lane.interval;
  lane.next = at + (sum >> 16);
  lane.fraction = sum & 0xFFFFu;
  lane.interval += static_cast<uint32_t>(lane.add);
  lane.left = 1;
}

// Starts playing ramp segment `seg` after the event at `at` (the lane folded before it).
HMC_STEP_INLINE void begin_ramp(StepLane& lane, const StepSegment& seg, uint32_t at) {
  lane.count = seg.count;
  lane.fraction = static_cast<uint16_t>(seg.position_step);
  lane.interval = seg.interval;
  lane.add = seg.add;
  lane.ramp_left = seg.count - 1;
  ramp_step(lane, at);
}

// Takes lane i's next segment, its `next` holding the last event's time. Drops what is left of a
// halted move; passes end markers. Leaves the lane armed on its next event, or not armed.
// Per segment (a ramp segment's start included): in RAM on the board.
HMC_STEP_RAMFUNC inline void load_segment(StepEngine& e, uint8_t i) {
  StepLane& lane = e.lanes[i];
  const uint8_t bit = uint8_t(1u << i);
  fold_steps(lane, lane.next);
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
    } else if ((flags & kSegRamp) != 0) {
      begin_ramp(lane, seg, lane.next);
      lane.flags = flags;
      e.armed = uint8_t(e.armed | bit);
      e.stepping = uint8_t(e.stepping | bit);
      fence();
      store8(lane.head, static_cast<uint8_t>(head + 1));
      return;
    } else {
      lane.next += seg.interval;
      if ((flags & kSegMove) != 0) {
        fold_position(lane, seg.position_step);
        lane.fired_from = lane.total;
      }
    }
    lane.interval = seg.interval;
    lane.count = seg.count;
    lane.left = seg.count;
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

// The main loop's requests for lane i: a halt first, then a ring to take up. Called on the
// interrupt's slow entry only: out of line, so its registers are not the fast path's.
HMC_STEP_RAMFUNC inline void take_lane_requests(StepEngine& e, uint8_t i) {
  StepLane& lane = e.lanes[i];
  const uint8_t bit = uint8_t(1u << i);
  const uint8_t halt = load8(lane.halt_request);
  if (halt != 0) {
    store8(lane.halt_request, 0);
    const uint8_t upto = load8(lane.halt_upto);
    if (static_cast<uint8_t>(upto - lane.head) <= kRingSize) store8(lane.head, upto);
    fold_steps(lane, lane.next);  // before the rest: a halted lane's last interval is 0
    const uint8_t end = halt & 0x7Fu;
    if (lane.moving != 0 && end != 0) {
      lane.end = end;
      ++lane.finished;
    }
    lane.moving = 0;
    e.armed = uint8_t(e.armed & ~bit);
    lane.last_interval = 0;
    ++lane.halts;
  }
  if ((e.armed & bit) == 0) load_segment(e, i);
}

// Lane i's due event is done (STEP raised if it steps): account for it, take the next.
HMC_STEP_INLINE void advance(StepEngine& e, uint8_t i) {
  StepLane& lane = *based(&e.lanes[i]);
  const uint32_t at = lane.next;
  if (HMC_STEP_UNLIKELY(--lane.left == 0)) {
    if (lane.ramp_left != 0) {  // a ramp segment's next step
      --lane.ramp_left;
      ramp_step(lane, at);
      return;
    }
    // A plain segment after a plain one: taken here, without the call; anything else (a ramp
    // segment, a start, an end, DIR, a wait, a replacing move, an empty ring) is load_segment's.
    const uint8_t head = lane.head;
    if (lane.flags == 0 && head != load8(lane.tail)) {
      fence();
      const StepSegment& seg = lane.ring[head & (kRingSize - 1)];
      // Not folded: `count` goes on counting, unless it would wrap (then count − left could
      // read 0 steps after 2³² of them).
      const uint32_t count = lane.count + seg.count;
      if (seg.flags == 0 && count >= seg.count) {
        lane.next = at + seg.interval;
        lane.interval = seg.interval;
        lane.count = count;
        lane.left = seg.count;
        fence();
        store8(lane.head, static_cast<uint8_t>(head + 1));
        return;
      }
    }
    load_segment(e, i);
  } else {
    lane.next = at + lane.interval;
  }
}

// Lane i's due event is done (STEP raised if it steps): its DIR, then its next event.
template <class Port>
HMC_STEP_INLINE void step_lane(StepEngine& e, Port& port, uint8_t i) {
  const uint8_t flags = e.lanes[i].flags;
  if (HMC_STEP_UNLIKELY((flags & kSegDir) != 0)) port.set_dir(i, (flags & kSegReverse) != 0);
  advance(e, i);
}

// An event `ahead` ticks away is beyond the compare's reach (never where it reaches every event
// time, kMaxSegmentTicks: a signed compare with a reach of 2^31 would wrap).
template <class Port>
HMC_STEP_INLINE bool beyond_reach(int32_t ahead) {
  if constexpr (Port::kReachTicks >= kMaxSegmentTicks) {
    return false;
  } else {
    return ahead >= static_cast<int32_t>(Port::kReachTicks);
  }
}

// Arms lane i's compare for its next event (or a relay on the way to it, or nothing when the
// lane has no event). False when the event is closer than the interrupt's own cost: the caller
// waits for it and raises it. Time has passed since entry, so the port's clock counts from the
// entry (or reads the clock), never from the event just made.
template <class Port>
HMC_STEP_INLINE bool arm_lane(StepEngine& e, StepLane& lane, Port& port, uint8_t i,
                              uint32_t entry, uint32_t entry_mark, bool waited) {
  const uint8_t bit = uint8_t(1u << i);
  if (HMC_STEP_UNLIKELY((e.armed & bit) == 0)) {
    port.disarm();  // the compare matches again only after its counter's wrap, raising nothing
    lane.compare = kCompareIdle;
    return true;
  }
  const uint32_t when = lane.next;
  const int32_t ahead = port.ticks_until(when, entry, entry_mark);
  if (HMC_STEP_UNLIKELY(ahead < static_cast<int32_t>(Port::kCostTicks))) return false;
  if (HMC_STEP_UNLIKELY(beyond_reach<Port>(ahead))) {
    // Beyond the compare's counter's reach: an entry on the way that steps nothing.
    const uint32_t at = when - static_cast<uint32_t>(ahead) + Port::kReachTicks;
    lane.relay_at = at;
    port.arm(at, false);
    lane.compare = kCompareRelay;
  } else {
    port.arm(when, (e.stepping & bit) != 0);
    lane.compare = kCompareEvent;
  }
  // After a wait inside, the old compare (an event this interrupt has made) may have matched
  // meanwhile: its flag would bring the next entry in early. The old value is past, so no
  // match comes before the new one is live.
  if (HMC_STEP_UNLIKELY(waited)) port.ack_event();
  return true;
}

}  // namespace step_engine_detail

// The express entry: the lane's armed event came, nothing is asked of the lane, and its next
// event steps in the same segment (a plain run's, or a ramp segment's next step) or in the next
// segment of the same kind, far enough ahead to arm and near enough for the compare to reach.
// Its STEP is the same, so only the pulse's end and the compare move (Port::rearm). Decided
// before anything changes: false leaves the entry to run_lane_general, untouched.
template <class Port>
HMC_STEP_INLINE bool run_lane_express(StepEngine& engine, Port& port) {
  using namespace step_engine_detail;
  StepLane& lane = *based(&engine.lanes[Port::kLane]);
  // flags, compare, pending and halt_request in one load: a plain run's or a ramp segment's
  // event armed, nothing asked.
  uint32_t state;
  __builtin_memcpy(&state, __builtin_assume_aligned(&lane, 4), sizeof state);
  const uint32_t at = lane.next;
  uint32_t when;
  uint32_t sum = 0;
  // The segment after this one's last event, of the same kind: a plain run (taken as advance()
  // takes it) or a ramp segment (taken as load_segment would: the steps folded, then begun).
  const StepSegment* run = nullptr;
  if (HMC_STEP_LIKELY(state == kExpressPlain)) {
    if (HMC_STEP_LIKELY(lane.left > 1)) {
      when = at + lane.interval;
    } else {
      // advance()'s test and work, written out in this entry's check-then-commit order (shared
      // helpers measured a cycle a step more here: scripts/bench cycles).
      const uint8_t head = lane.head;
      if (head == load8(lane.tail)) return false;
      fence();
      run = &lane.ring[head & (kRingSize - 1)];
      if (run->flags != 0 || lane.count + run->count < run->count) return false;
      when = at + run->interval;
    }
  } else if (state == kExpressRamp) {
    if (HMC_STEP_LIKELY(lane.ramp_left != 0)) {
      sum = lane.fraction + lane.interval;  // ramp_step's, not yet stored
    } else {
      const uint8_t head = lane.head;
      if (head == load8(lane.tail)) return false;
      fence();
      run = &lane.ring[head & (kRingSize - 1)];
      if (run->flags != kSegRamp) return false;
      sum = static_cast<uint16_t>(run->position_step) + run->interval;  // begin_ramp's
    }
    when = at + (sum >> 16);
  } else {
    return false;
  }
  if (HMC_STEP_UNLIKELY(((when - at) >> kExpressBits) != 0) ||
      HMC_STEP_UNLIKELY(!port.event_fired(engine))) {
    return false;
  }
  const int32_t ahead = port.ticks_until(when, at, 0);
  if (HMC_STEP_UNLIKELY(ahead < static_cast<int32_t>(Port::kCostTicks))) return false;
  // The event just made is past, so the next is less than kExpressTicks away: only a compare
  // that reaches less than twice that (TCC2's) may need a relay.
  if (Port::kReachTicks < 2 * kExpressTicks && HMC_STEP_UNLIKELY(beyond_reach<Port>(ahead))) {
    return false;
  }
  port.fired(at);  // first: on the host this raises STEP
  const uint32_t mark = port.stopwatch();
  port.ack_event();
  lane.next = when;
  port.rearm(when);
  if (HMC_STEP_LIKELY(run == nullptr)) {
    if (HMC_STEP_LIKELY(state == kExpressPlain)) {
      --lane.left;
    } else {
      --lane.ramp_left;
      lane.fraction = sum & 0xFFFFu;
      lane.interval += static_cast<uint32_t>(lane.add);
    }
  } else {
    if (state == kExpressPlain) {
      lane.interval = run->interval;
      lane.count += run->count;
      lane.left = run->count;
    } else {
      lane.left = 0;  // the segment played out, as advance() leaves it for load_segment
      fold_steps(lane, at);
      begin_ramp(lane, *run, at);
    }
    fence();
    store8(lane.head, static_cast<uint8_t>(lane.head + 1));
  }
  port.step_low(mark);
  return true;
}

// Lane Port::kLane's interrupt (see the top of this file) in full: its compare's event, a relay,
// or the main loop's request.
template <class Port>
HMC_STEP_INLINE void run_lane_general(StepEngine& engine, Port& port) {
  using namespace step_engine_detail;
  constexpr uint8_t i = Port::kLane;
  constexpr uint8_t bit = uint8_t(1u << i);
  StepEngine& e = *based(&engine);
  StepLane& lane = e.lanes[i];
  const uint8_t compare = lane.compare;
  const bool fired = port.event_fired(e);
  uint32_t now;
  bool raised = false;  // STEP raised by this entry (the host's, or the CPU's), not yet lowered
  bool waited;
  if (HMC_STEP_LIKELY(fired && compare != kCompareIdle && load8(lane.pending) == 0)) {
    if (HMC_STEP_LIKELY(compare == kCompareEvent)) {
      now = lane.next;
      if ((e.stepping & bit) != 0) {
        port.fired(now);  // first: on the host this raises STEP
        raised = !Port::kArmedStepsByHardware;
      }
      port.ack_event();
      step_lane(e, port, i);
    } else {
      port.ack_event();
      now = lane.relay_at;
    }
    waited = false;
  } else {
    if (load8(lane.pending) == 0) {
      // Neither its compare's event nor a request: another lane's kick, or a parked compare
      // come round with its counter.
      if (fired) port.ack_event();
      return;
    }
    // The armed event may have come: it is taken as made, before a halt could drop it
    // uncounted. Its compare's flag tells, not the clock (a lane's timer and the clock agree only
    // to its offset's measure), read just before the disarm and just after. Set before: the
    // hardware raised STEP, perhaps long ago, and raising it again would be a second step. Set
    // only after: the match came a few cycles ago, about the disarm, and may have found the mask
    // 0: the CPU raises STEP at once, which a STEP the hardware did raise, still high then, does
    // not see as a second edge.
    const bool before = compare == kCompareEvent && port.event_fired(e);
    port.disarm();
    if (Port::kArmedStepsByHardware) {
      const bool came = before || (compare == kCompareEvent && port.event_fired(e));
      if (came && !before && (e.stepping & bit) != 0) port.step_high(lane.next);
      // The compare is moved to now (past once live, and a whole counter's wrap from matching
      // again: a parked compare comes round every 2^16 ticks on a 16-bit timer), so nothing the
      // hardware does at it can touch a pulse this entry makes.
      now = port.take_entry();
      port.park(now);
      if (came) step_lane(e, port, i);
    }
    lane.compare = kCompareIdle;
    store8(lane.pending, 0);
    take_lane_requests(e, i);
    // The clock after the requests: the waits and the compare count from here.
    now = port.take_entry();
    waited = true;
  }
  // The entry's mark: waits and the time spent count from here.
  const uint32_t entry_mark = port.stopwatch();
  const uint32_t entry = now;
  uint32_t mark = entry_mark;
  while (HMC_STEP_UNLIKELY(!arm_lane(e, lane, port, i, entry, entry_mark, waited))) {
    // Due before the interrupt could return and come back: waited for, raised by the CPU.
    if (raised) port.step_low(mark);
    const uint32_t when = lane.next;
    port.wait_until(when, entry, entry_mark);
    raised = (e.stepping & bit) != 0;
    if (raised) port.step_high(when);
    mark = port.stopwatch();
    step_lane(e, port, i);
    waited = true;
  }
  if (raised) port.step_low(mark);
}

// The interrupt: the express entry, or the full one.
template <class Port>
HMC_STEP_INLINE void run_lane_interrupt(StepEngine& engine, Port& port) {
  if (!run_lane_express(engine, port)) run_lane_general(engine, port);
}

}  // namespace hmc::fw
