// StepScheduler: the main loop's side of the step engine (step_engine.h). It plans moves
// (ramp.h), computes every step's exact time ahead, and keeps each motor's ring of segments
// filled a handover lead ahead of the clock; the step interrupt only plays the rings back.
//
// Timing model. Event times are exact ticks: a step is scheduled for its ideal time rounded to
// the tick (ramp.h defines the ideal profile), so within half a tick of it, and counted as
// happening then; the pin moves after the interrupt's latency. Lateness never accumulates: each
// time comes from the profile, never from when an interrupt ran. Rings carry the exact times as
// {interval, count} segments (a ramp step is a segment of one, a cruise a segment of many), so
// the playback adds no error at all: the bound is the planner's half tick (plus the 2⁻¹⁶ and
// integer-K terms of ramp.h, far below a tick), within the one tick the engine promises.
//
// Pulses (DRV8711 datasheet, SLVSC40, "Timing Requirements": STEP high ≥ 1.9 µs, low ≥ 1.9 µs,
// DIR setup and hold ≥ 200 ns around a STEP edge):
//  - STEP goes high at the step's time and low kStepHighTicks (96 = 2.0 µs) after the pin moved:
//    by DMA on the board (targets/samd21/step_pulses.h), inside the interrupt on the host
//    (step_engine.h);
//  - a move's interval is at least kMinIntervalTicks (240 = 5 µs); a step is never planned
//    less than kStepHighTicks + kStepLowTicks after the previous one, nor less than
//    kDirGuardTicks after a DIR change (clamped_edges() counts the clamps, which no valid plan
//    needs);
//  - DIR changes only when a move starts from rest, as an event of its own ≥ kDirGuardTicks
//    after the last pulse ended and ≥ kDirGuardTicks before the first step.
//
// Moves. start() plans a move in the main loop, where dividing is allowed.
//  - From rest: the move's anchor t₀ is the clock when start() runs (later if the last pulse or
//    a DIR change needs it, or if the first step would come less than kPickupTicks after it:
//    a constant-rate move under 100 µs a step starts that much later). Step j is at t₀ + j·I at constant rate; 10 000 steps at 100 µs
//    (4 800 ticks) put the last rising edge exactly 48 000 000 ticks (1.000 s) after t₀.
//  - A move for a running motor replaces its move at the handover step h: the first step not
//    yet in the ring. The ring reaches `handover_lead` ahead of the clock (at least one step),
//    so a replacement takes effect within about that lead. Same direction: the new profile
//    starts from the old one's ideal speed at step h, anchored at step h's rising edge (ramp.h,
//    "from speed u"). Reverse: with an acceleration the motor brakes to rest first (as stop()
//    does) and the new move starts from rest; at constant rate it stops at once and starts the
//    new move from rest.
//  - stop(): with an acceleration, brake at it from step h to rest; at constant rate, stop at
//    once (as halt()).
//  - halt(), halt_all(): stop at once: no rising edge after the interrupt takes the halt, which
//    the call triggers at once.
//
// Positions are in 1/256 step: a step at microstep m moves 256/m (signed by direction).
//
// Contexts. start, stop, fill, set_position and the queries run in the main loop, which must
// call fill() more often than the lead (Controller::poll does; a late fill makes the ring run
// dry, which starved_events() counts). halt and halt_all may also run in an interrupt (a limit
// switch) that does not preempt the step interrupt; a start() such an interrupt preempts may
// still take effect after the halt. Nothing here calls back into the controller: the main loop
// polls finished() to learn that a motion ended.
//
// Freestanding: no heap, no exceptions, no library; each motor holds four Profile slots.
#pragma once

#include <stdint.h>

#include "hal.h"
#include "ramp.h"
#include "step_engine.h"

namespace hmc::fw {

inline constexpr uint32_t kStepLowTicks = 96;   // 2 µs: the shortest STEP low time allowed
inline constexpr uint32_t kDirGuardTicks = 10;  // 208 ns
// A move from rest has its first step at least this long after start() reads the clock: the
// ring's first fill and the interrupt's taking it come first (on the image, from the clock's
// read to the compare armed, ≈ 3 400 ticks with the planning, which now comes before the read).
// Anchored at the clock alone, a 20 µs move's first steps were already past when the interrupt
// took them: it raised them back to back, too close to be pulses at all.
inline constexpr uint32_t kPickupTicks = 4800;  // 100 µs
// From rest at up to this acceleration (steps/s²) the first step comes √(2/a) s ≥ kPickupTicks
// after the anchor (2·48 000 000² / 4 800²).
inline constexpr uint32_t kPickupAccel = 200000000;

enum class StepStatus : uint8_t {
  kOk,
  kBadMotor,       // not 1..3
  kBadMicrostep,   // see PlanStatus
  kIntervalShort,
  kBadAccel,
  kRampTooLong,
};

// Why a motor's last motion ended.
enum class MoveEnd : uint8_t { kNone, kCompleted, kStopped, kHalted };

class StepScheduler {
 public:
  static constexpr uint8_t kMotors = 3;
  // How far ahead of the clock the rings reach: the main loop must run fill() within this.
  static constexpr hal::Ticks kDefaultHandoverLead = 96000;  // 2 ms

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
  // Main loop: tops the rings up to the lead ahead of the clock.
  void fill();

  // The step timer's interrupt over the HAL interfaces (the simulator, the tests): each lane's
  // interrupt whose compare is due or whose request is pending. The SAMD21 runs
  // run_lane_interrupt() on engine() from each motor's own compare interrupt instead.
  void on_step_timer();
  StepEngine& engine() { return engine_; }

  // Queries (main loop). A motor runs from start() until its motion ends.
  bool is_running(uint8_t motor) const;
  int32_t position(uint8_t motor) const;      // 1/256 step
  uint32_t steps_done(uint8_t motor) const;   // steps of the current (or last) move
  // Where the planned motion ends (the position at rest); false while it runs until stopped.
  bool target(uint8_t motor, int32_t& out) const;
  uint32_t interval(uint8_t motor) const;     // ticks between its last two rising edges; 0 at rest
  uint32_t rate(uint8_t motor) const;         // steps/s from interval(); 0 at rest
  uint32_t finished(uint8_t motor) const;     // motions ended so far (poll for a change)
  MoveEnd last_end(uint8_t motor) const;
  uint32_t clamped_edges() const;             // safety clamps applied (0 with valid plans)
  uint32_t starved_events() const;            // events that found their ring empty

 private:
  static constexpr uint8_t kSlots = 4;
  static constexpr uint8_t kNoSlot = 0xFF;

  // The main loop's plan of one motor: the profile playing into the ring and the per-step math.
  struct Motor {
    hal::Ticks base;        // sqrt phase: base tick; cruise: the next step
    hal::Ticks anchor;
    hal::Ticks last_rise;   // the last step pushed
    hal::Ticks last_event;  // the last event pushed
    hal::Ticks rise_ok_at;  // earliest allowed next step
    uint64_t m;
    uint64_t k;
    uint64_t x;             // sqrt phase: ⌊m/k⌋, the position on the ramp from rest (steps)
    int64_t rest;           // m − root², after an exact step
    uint32_t left;          // steps left in the phase
    uint32_t root;
    uint32_t root_step;
    uint32_t g;
    uint32_t kappa;         // ⌊√k⌋ + 1
    uint32_t fraction;      // after a ramp segment: the interrupt's fraction of a tick (Q0.16)
    int64_t next_interval;  // after a ramp segment: its interval and add carried on (Q16)
    int64_t next_add;
    uint32_t segment_steps; // steps of the phase's last ramp segment (its first: 256)
    uint32_t fits_up_to;    // accelerating: the longest segment the bound allowed so far
    uint32_t refused_from;  // braking: the shortest segment the bound refused so far
    uint32_t allowed;       // steps_ahead_allowed() for last_delta = allowed_for
    uint32_t allowed_for;
    uint32_t cruise_interval;
    uint32_t last_delta;    // between the last two steps pushed
    uint32_t planned;       // steps of the active move pushed
    uint32_t pushed;        // steps pushed since power-up (wraps, as StepLane::total)
    uint32_t profile_base;  // `pushed` when the active profile began
    uint32_t switch_at;     // with a next_slot: the active profile's last step before it
    uint32_t seen_halts;    // StepLane::halts when DIR was last known
    uint32_t refill_total;  // StepLane::total at which produce() has steps to push again
    int32_t pushed_position;  // the position after every step pushed
    PhaseKind kind;
    uint8_t phase;
    uint8_t active;         // slot playing into the ring, kNoSlot when none
    uint8_t then_slot;      // slot to start from rest when the active one ends
    uint8_t next_slot;      // slot replacing the active one after step switch_at, or kNoSlot
    uint8_t next_then;      // the then_slot that comes with it
    bool started;           // a move has started since power-up (last_rise is meaningful)
    bool dir_known;
    bool dir_reverse;
    bool move_mark;         // the next step segment begins a replacing move
    bool in_phase;          // a step of the current sqrt phase is pushed: segments may follow
    bool after_ramp;        // the last step pushed ended a ramp segment (`fraction` holds)
    Profile slots[kSlots];
  };

  StepStatus plan_and_post(uint8_t motor, const MoveSpec* move);
  void sync(uint8_t index);
  void produce(uint8_t index);
  void begin_from_rest(uint8_t index, uint8_t slot, hal::Ticks soonest);
  hal::Ticks soonest_start(const Profile& profile) const;
  void begin_profile(Motor& mo, uint8_t slot, hal::Ticks anchor);
  void finish(uint8_t index);
  bool next_run(Motor& mo, uint32_t most, hal::Ticks& first, uint32_t& count);
  uint32_t push_ramp_segment(uint8_t index, uint32_t most);
  int64_t ideal_offset_q16(const Motor& mo) const;
  void push(uint8_t index, const StepSegment& seg);
  uint8_t space(uint8_t index) const;
  uint32_t steps_ahead_allowed(Motor& mo) const;
  void post_halt(uint8_t index, uint8_t end);
  void wake(uint8_t index);
  void kick();

  hal::StepTimer& timer_;
  hal::StepPins& pins_;
  uint32_t lead_;  // ticks (a 32-bit division on the M0+ is a short helper; 64-bit is long)
  uint32_t clamped_;
  StepEngine engine_;
  Motor motors_[kMotors];
};

}  // namespace hmc::fw
