// StepScheduler: one hardware timer steps all three motors, each on its own schedule.
//
// Timing model. Every motor has one pending event: a STEP rising edge, the falling edge that
// ends it, or the start of a move. The interrupt (on_step_timer) handles every event that is
// due, in time order, and programs the timer for the earliest one left (Klipper's timer list,
// with three entries). Event times are exact ticks: an edge is scheduled for its ideal time
// rounded to the tick (ramp.h defines the ideal profile) and counted as happening then; the pin
// itself moves after the interrupt's latency, and later still by the work of other motors'
// edges due in the same few microseconds. Lateness never accumulates: the next edge is computed
// from the schedule, not from when the interrupt ran.
//
// Pulses (DRV8711: STEP high ≥ 1.9 µs, low ≥ 1.9 µs, DIR stable 200 ns around a STEP edge):
//  - STEP goes high at the step's time and low kStepHighTicks (120 = 2.5 µs) later, as its
//    own timer event, never a busy wait;
//  - a move's interval is at least kMinIntervalTicks (240 = 5 µs): at most 200 000 steps/s,
//    leaving STEP low ≥ 2.5 µs (a ramp joint rounded a tick short leaves ≥ 2.48 µs). A
//    rising edge is never scheduled less than kStepLowTicks after the last falling edge nor
//    less than kDirGuardTicks after a DIR change (clamped_edges() counts the clamps, which
//    no valid plan needs);
//  - DIR changes only when a move starts from rest, with STEP low, ≥ kDirGuardTicks (10 =
//    208 ns) after the last falling edge and ≥ kDirGuardTicks before the next rising edge;
//  - the high and low times count from when the pin actually moved (the clock is read after
//    each STEP write), so an interrupt running late makes edges late, never pulses short.
//
// Cost on the SAMD21 (Cortex-M0+, -Os; instruction-level emulation with M0+ cycle counts, HAL
// calls as virtual calls, plus ~30 cycles of exception entry and exit per interrupt): a step
// takes two interrupts, ≈ 750 cycles at constant rate (≈ 64 000 steps/s on one motor), ≈ 990
// while ramping (median; ≈ 49 000 steps/s; the ramp math itself is ≈ 300 cycles, 99 % under
// 860), ≈ 1 170 per step with three motors ramping (≈ 41 000 steps/s in all). The first steps
// of a ramp cost up to ≈ 2 300 cycles of math, at intervals of milliseconds. So on the board
// the interrupt, not the driver, bounds the rate; the planner accepts the driver's 5 µs, which
// the host simulator reaches.
//
// Moves. start() plans a move (ramp.h) in the main loop, where dividing is allowed, and hands
// the interrupt a finished Profile; the interrupt only adds, multiplies, compares and shifts.
//  - From rest: the move's anchor t₀ is the tick the interrupt takes it up (at once when the
//    motor is idle). Step j is at t₀ + j·I at constant rate; 10 000 steps at 100 µs
//    (4 800 ticks) put the last rising edge exactly 48 000 000 ticks (1.000 s) after t₀, the
//    first and the last 9 999 intervals apart.
//  - A move for a running motor replaces its move at a handover step h: the first step whose
//    time is not yet fixed, plus enough steps to cover `handover_lead` (the planning time).
//    Same direction: the new profile starts from the old one's ideal speed at step h, anchored
//    at step h's rising edge (ramp.h, "from speed u"). Reverse: with an acceleration the motor
//    brakes to rest first (as stop() does) and the new move starts from rest; at constant rate
//    it stops at once and starts the new move from rest.
//  - stop(): with an acceleration, brake at it from step h to rest (the motor ends past the
//    point of the command); at constant rate, stop at once (as halt()).
//  - halt(), halt_all(): stop at once: no rising edge after the interrupt takes the halt,
//    which the call triggers at once; a STEP already high still gets its falling edge.
//
// Positions are in 1/256 step: a step at microstep m moves 256/m (signed by direction).
//
// Contexts. start, stop, set_position and the queries run in the main loop. halt and halt_all
// may also run in an interrupt (a limit switch) that does not preempt on_step_timer; a start()
// such an interrupt preempts may still take effect after the halt. Nothing here calls back into
// the controller: the main loop polls finished() to learn that a motion ended.
//
// Freestanding: no heap, no exceptions, no library; each motor holds four Profile slots.
#pragma once

#include <stdint.h>

#include "hal.h"
#include "ramp.h"

namespace hmc::fw {

inline constexpr uint32_t kStepLowTicks = 96;   // 2 µs: the shortest STEP low time allowed
inline constexpr uint32_t kDirGuardTicks = 10;  // 208 ns

enum class StepStatus : uint8_t {
  kOk,
  kBadMotor,       // not 1..3
  kBadMicrostep,   // see PlanStatus
  kIntervalShort,
  kBadAccel,
  kRampTooLong,
  kBusy,           // the interrupt kept overtaking the handover (never with a sane lead)
};

// Why a motor's last motion ended.
enum class MoveEnd : uint8_t { kNone, kCompleted, kStopped, kHalted };

class StepScheduler {
 public:
  static constexpr uint8_t kMotors = 3;
  // Planning on the M0+ takes ≈ 0.63 ms for a replacement, 0.78 ms for a reverse, 0.28 ms
  // for a stop (measured as above); a handover 2 ms ahead leaves room for the interrupts.
  static constexpr hal::Ticks kDefaultHandoverLead = 96000;

  StepScheduler(hal::StepTimer& timer, hal::StepPins& pins,
                hal::Ticks handover_lead = kDefaultHandoverLead);

  // Main loop: starts `move` on motor 1..3 (or replaces its move).
  StepStatus start(uint8_t motor, const MoveSpec& move);
  // Main loop: brakes to rest (acceleration) or stops at once (constant rate).
  StepStatus stop(uint8_t motor);
  // Any context (see above): stop at once, never braking.
  void halt(uint8_t motor);
  void halt_all();
  // Main loop: sets the position of an idle motor (homing). False while it runs.
  bool set_position(uint8_t motor, int32_t position);

  // The step timer's interrupt.
  void on_step_timer();

  // Queries (main loop). A motor runs from start() until its motion ends.
  bool is_running(uint8_t motor) const;
  int32_t position(uint8_t motor) const;      // 1/256 step
  uint32_t steps_done(uint8_t motor) const;   // steps of the current (or last) move
  // Where the playing profile ends (the position at rest); false while it runs until stopped.
  bool target(uint8_t motor, int32_t& out) const;
  uint32_t interval(uint8_t motor) const;     // ticks between its last two rising edges; 0 at rest
  uint32_t rate(uint8_t motor) const;         // steps/s from interval(); 0 at rest
  uint32_t finished(uint8_t motor) const;     // motions ended so far (poll for a change)
  MoveEnd last_end(uint8_t motor) const;
  uint32_t clamped_edges() const;             // safety clamps applied (0 with valid plans)

 private:
  static constexpr uint8_t kSlots = 4;
  static constexpr uint8_t kNoSlot = 0xFF;
  static constexpr hal::Ticks kNever = ~hal::Ticks{0};

  enum class Event : uint8_t { kNone, kRise, kFall, kStart };
  enum class Ask : uint8_t { kNone, kQueue, kReplace, kHaltThen };

  // The main loop's request to the interrupt. The main loop writes the fields, then `kind`;
  // the interrupt clears `kind` when it takes the request.
  struct Request {
    Ask kind;
    uint8_t slot;       // kQueue / kHaltThen: the move to start from rest (kNoSlot: none)
    uint8_t then_slot;  // kReplace: the move to start from rest after `slot` ends
    uint32_t at_step;   // kReplace: take `slot` up when step at_step falls
  };

  struct Motor {
    // The interrupt's per-edge state, first: the M0+ reaches a field beyond 124 bytes only
    // through an extra address computation.
    hal::Ticks event_at;
    hal::Ticks last_rise;
    hal::Ticks base;        // sqrt phase: base tick; cruise: the next step
    hal::Ticks rise_ok_at;  // earliest allowed rising edge
    uint64_t m;
    uint64_t k;             // of the active profile
    const Profile* profile; // the active profile, null when none
    Event event;
    PhaseKind kind;         // of the phase playing
    uint8_t phase;          // index of the phase playing, kNoSlot before the first
    uint8_t number;         // 1..3, for the pins
    int16_t position_step;
    bool step_high;
    bool dir_known;
    uint32_t left;          // steps left in the phase
    uint32_t root;          // floor(√m)
    uint32_t root_step;     // the root's last change: the next guess
    uint32_t g;             // 1 − h in 2⁻¹⁶, 0 for h = 0
    uint32_t cruise_interval;
    // Written by the interrupt, read by the main loop.
    uint32_t fired;         // rising edges of the active move
    uint32_t planned;       // steps of the active move whose time is fixed
    uint32_t interval;
    uint32_t gen;           // bumped whenever active/queued change or a request is taken
    uint32_t finished;
    int32_t position;
    uint8_t active;         // slot playing, kNoSlot when none
    uint8_t queued;         // slot to start from rest when the active one ends
    MoveEnd end;
    // Written by the main loop, read by the interrupt.
    uint8_t halt_request;   // a MoveEnd: kHalted, or kStopped for stop() at constant rate
    Request request;
    // The interrupt's own, seldom used.
    bool dir_reverse;
    hal::Ticks anchor;
    hal::Ticks dir_ok_at;   // earliest allowed DIR change
    Profile slots[kSlots];
  };

  // The main loop and the interrupt share plain fields; these keep the compiler from caching or
  // reordering them across the hand-over points (one core: a signal fence is enough).
  template <typename T>
  static T load(const T& x) {
    return *static_cast<const volatile T*>(&x);
  }
  template <typename T>
  static void store(T& x, T value) {
    *static_cast<volatile T*>(&x) = value;
  }
  static void fence() { __atomic_signal_fence(__ATOMIC_SEQ_CST); }

  // Main loop (step_scheduler.cpp).
  StepStatus plan_and_post(uint8_t motor, const MoveSpec* move);
  bool post_replace(Motor& mo, uint32_t gen, uint32_t at_step, uint8_t slot, uint8_t then_slot);
  void post(Motor& mo, Ask kind, uint8_t slot);
  void post_halt(Motor& mo, MoveEnd end);
  void kick();

  // Interrupt (step_scheduler_isr.cpp).
  void take_requests(Motor& mo, hal::Ticks now);
  void on_fall(Motor& mo);
  void on_start(Motor& mo);
  void halt_now(Motor& mo, MoveEnd end);
  void begin_profile(Motor& mo, uint8_t slot, hal::Ticks anchor);
  void plan_next(Motor& mo);
  void finish(Motor& mo);
  bool next_step_time(Motor& mo, hal::Ticks& out);

  hal::StepTimer& timer_;
  hal::StepPins& pins_;
  hal::Ticks lead_;
  uint32_t clamped_;
  uint8_t pending_;  // set by the main loop: a request or a halt waits
  Motor motors_[kMotors];
};

}  // namespace hmc::fw
