// Ramp planning: turns a move (direction, microstep, steps, interval, acceleration) and the
// speed the motor already has into a Profile, the list of at most three phases the step
// interrupt plays back with the division-free math of step_math.h.
//
// Units. Time in ticks of the 48 MHz step timer (F = 48 000 000 per second). A move's rate is
// its interval I (ticks per step, v = F/I steps/s). For an acceleration a (steps/s²) let
// K = 2F²/a (ticks² per step). A speed u is carried as its velocity time τ = u·F/a, the ticks
// the ramp needs to reach u from rest, or as M = τ² (ticks²): the ramp from rest reaches position
// x when M = x·K. So M is the position on the ramp, and each step adds or removes K.
//
// The ideal profile of a move (what every step time is measured against). Positions count the
// move's steps from its anchor: the tick t₀ at which the move starts from rest, or the rising
// edge of the last step of the move it replaces. Step j happens when the ideal position x(t)
// reaches j (j = 1..N). From speed u the ideal changes speed at ±a toward v, holds v, and brakes
// at a to reach rest exactly at x = N:
//   from rest, trapezoid (N ≥ 2x_v, x_v = v²/2a = M_v/K):
//     acceleration  j ≤ x_v:            t_j = t₀ + √(jK)                      (= √(2j/a) s)
//     cruise        x_v < j < N − x_v:  t_j = t₀ + j·I + T_v/2                 (T_v = v/a, ticks)
//     braking       j ≥ N − x_v:        t_j = t₀ + N·I + T_v − √((N − j)K)
//   the phases join where the speed reaches v (x = x_v) and where braking starts (x = N − x_v):
//   position and speed are continuous there, so both neighbouring formulas give the same time
//   at the joins;
//   from rest, triangle (N < 2x_v): acceleration for j ≤ N/2, braking for j ≥ N/2, with
//     t_j = t₀ + 2√(NK/2) − √((N − j)K) while braking;
//   from speed u (a replacement, M_u = τ_u²): acceleration t_j = t₀ − τ_u + √(M_u + jK) while
//     M_u + jK ≤ M_v, or slowing t_j = t₀ + τ_u − √(M_u − jK) while M_u − jK ≥ M_v; cruise
//     t_j = t₀ + j·I ± (T_v − τ_u)²/(2T_v) (+ after accelerating, − after slowing); braking from
//     t_end = t₀ + N·I + T_v/2 ± (T_v − τ_u)²/(2T_v); a triangle peaks at M_p = (NK + M_u)/2;
//   a move shorter than the stopping distance from u (N·K < M_u) cannot stop at its target
//     without braking harder than a: it brakes at a, t_j = t₀ + τ_u − √(M_u − jK), and ends
//     floor(M_u/K) steps out, past the target (as a stop does).
//   N = 0 (run until stopped) has no braking phase. a = 0 has no ramps: t_j = t₀ + j·I.
//
// Each scheduled step is the ideal time rounded to the nearest tick, so within half a tick of
// it, plus two errors kept far below a tick: K, M_v and the entry M are integers (K = 2F²/a
// rounded: after j steps M is off by j/2 at most, which moves √M by √(j/K)/4 < 1/(8·I) tick),
// and the phases' offsets carry 16 fractional bits.
//
// The split: planning here divides (64-bit and 128-bit long division, square roots with 16
// fractional bits) and runs in the main loop when a move starts. The interrupt only adds K to
// M, corrects the previous root by the change of the previous step (step_math.h), compares once
// to round, and adds; cruise steps add I. Valid ramps need T_v ≤ 2³⁰ ticks (22.4 s): M < 2⁶⁰.
#pragma once

#include <stdint.h>

namespace hmc::fw {

inline constexpr uint64_t kStepTicksPerSecond = 48000000;
// Ticks the STEP line stays high (2.0 µs; the DRV8711 needs 1.9 µs, SLVSC40 "Timing
// Requirements"), timed inside the step interrupt, and the shortest interval a move may ask
// for: 5 µs, at most 200 000 steps/s on one motor (the controller's budget bounds the sum).
inline constexpr uint32_t kStepHighTicks = 96;
inline constexpr uint32_t kMinIntervalTicks = 240;
// The longest velocity time a ramp may have (T_v = v/a), and so the largest M.
inline constexpr uint64_t kMaxRampTicks = uint64_t{1} << 30;
// Number of steps of an endless cruise phase.
inline constexpr uint32_t kEndless = 0xFFFFFFFFu;

struct MoveSpec {
  bool reverse;        // direction line level: false forward, true reverse
  uint16_t microstep;  // 1, 2, 4 … 256: each step moves 256/microstep position units
  uint32_t steps;      // 0 = run until stopped
  uint32_t interval;   // ticks per step at the commanded rate, ≥ kMinIntervalTicks
  uint32_t accel;      // steps/s², 0 = constant rate (the seed's behaviour)
};

enum class PlanStatus : uint8_t {
  kOk,
  kBadMicrostep,   // not a power of two in 1..256
  kIntervalShort,  // below kMinIntervalTicks
  kBadAccel,       // above 2³¹ − 1 steps/s²
  kRampTooLong,    // a velocity time above kMaxRampTicks (acceleration too low for the rate)
};

enum class PhaseKind : uint8_t { kUp, kDown, kCruise };

// One phase of a profile. Sqrt phases: step time = base ± floor(√M + h) with M changed by ±K per
// step before use, base = reference tick + offset. Cruise: first step at reference + offset, then
// every `interval`. The reference is the profile's anchor, or, with from_last_step, the rising
// edge of the previous phase's last step.
struct Phase {
  PhaseKind kind;
  bool from_last_step;
  uint16_t h;           // sqrt phases: the rounding fraction h in units of 2⁻¹⁶
  uint32_t steps;       // steps in the phase (kEndless: endless cruise)
  uint32_t root;        // floor(√m)
  uint32_t root_step;   // change of the root at the first step (the interrupt's first guess)
  uint32_t interval;    // cruise
  uint64_t m;           // M before the first step of the phase
  int64_t offset;       // ticks from the reference
};

struct Profile {
  MoveSpec spec;
  Phase phases[3];
  uint8_t phase_count;
  bool stopping;         // ends a stop() rather than a move
  bool endless;          // runs until stopped
  int16_t position_step; // ±256/microstep
  uint32_t total_steps;  // steps in the profile (when not endless)
  uint64_t k;            // ticks² per step; 0 for a constant-rate profile
  uint64_t m_entry;      // M at the anchor (the speed the profile starts from)
  uint64_t m_cruise;     // M of the commanded rate
};

// Checks a move's own fields.
PlanStatus check_move(const MoveSpec& spec);

// Plans `spec` from the speed whose M (in spec's units) is m_entry; 0 = from rest.
PlanStatus plan_move(const MoveSpec& spec, uint64_t m_entry, Profile& out);

// Plans a stop: braking at spec.accel (> 0) from m_entry to rest, in spec's direction.
PlanStatus plan_stop(const MoveSpec& spec, uint64_t m_entry, Profile& out);

// The ideal speed of `profile` at its step `step` (0 = its anchor), as M in the units of `to`
// (its acceleration and microstep). Gives 0 when `to` has no acceleration.
PlanStatus speed_at(const Profile& profile, uint32_t step, const MoveSpec& to, uint64_t& m_out);

// Integer helpers (main-loop context; they divide).
namespace ramp_math {
uint32_t isqrt(uint64_t x);           // floor(√x)
uint64_t isqrt_q16(uint64_t x);       // floor(√x · 2¹⁶), x < 2⁶²
uint64_t mul_div(uint64_t a, uint64_t b, uint64_t c);  // floor(a·b/c); saturates at 2⁶⁴ − 1
}  // namespace ramp_math

}  // namespace hmc::fw
