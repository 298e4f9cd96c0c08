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
// Each step pushed alone is the ideal time rounded to the nearest tick, so within half a tick of
// it (a step of a ramp segment within one tick: "Ramp segments" below), plus two errors kept far
// below a tick: K, M_v and the entry M are integers (K = 2F²/a
// rounded: after j steps M is off by j/2 at most, which moves √M by √(j/K)/4 < 1/(8·I) tick),
// and the phases' offsets carry 16 fractional bits.
//
// The split: planning here divides (64-bit and 128-bit long division, square roots with 16
// fractional bits) and runs in the main loop when a move starts. The main loop then works out
// step times (step_scheduler.cpp, step_math.h: M += K, the previous root corrected, one compare
// to round) and the interrupt plays them; cruise steps add I. Valid ramps need T_v ≤ 2³⁰ ticks
// (22.4 s): M < 2⁶⁰.
//
// Ramp segments: the interrupt adds, the main loop computes a few exact points per segment.
// Within a square-root phase the main loop does not push every step: it pushes a segment of n
// steps (n a power of two, 2 ≤ n ≤ kMaxRampSegmentSteps) that the interrupt plays with adds
// only. In ticks with 16 fractional bits (Q16), per lane: an accumulator A (the next event's
// tick plus a fraction f), an interval d and an add s; per step A += d, d += s, and the step
// rises at floor(A). Over a segment A is the quadratic A_k = A_0 + k·d + k(k−1)/2·s (k = 0..n,
// k = 0 the step before the segment), which the main loop fits through A_0 (its exact copy of
// the interrupt's accumulator: A never resets between ramp segments, so rounding does not
// drift) and the ideal X_k = τ_k + ½ at k = n/2 and k = n (τ_k the ideal time, ½ so that the
// floor rounds): with m = n/2, s = (Δ_n − 2Δ_m)/m² and d = (Δ_n − n(n−1)/2·s)/n, Δ_k = X_k − A_0
// (shifts, m being a power of two; s rounded first and d then chosen so A_n lands on X_n).
// The bound, every step within one tick of the ideal: |floor(A_k) − τ_k| ≤ ½ + |A_k − X_k|, and
//   |A_k − X_k| ≤ E_interp + E_fixed, required ≤ ½.
// E_interp, the quadratic through three points of f(k) = ±√(M₀ ± kK) (k real): at most
//   max|f'''|·max|k(k − m)(k − n)|/6 = max|f'''|·n³·√3/216, with |f'''| = 3K³/(8M^{5/2}) largest
//   at the segment's smallest M. With x = M/K (the position on the ramp from rest, steps):
//   E_interp ≤ (√3/576)·n³·√K/x_min^{5/2}. The main loop takes n only if
//     n³·κ ≤ 124·x_lo²·⌊√x_lo⌋   (κ = ⌊√K⌋ + 1 ≥ √K, x_lo = ⌊x_min⌋ ≤ x_min, 124 < 3·576/(8√3))
//   so E_interp ≤ ⅜. n = 2 needs no test (its nodes are its steps: E_interp = 0). A segment is
//   therefore short at the start of a ramp from rest (x small: n ∝ x^{5/6}/K^{1/6}) and at the
//   end of braking, and long near cruise speed (x large); x_min is the segment's first point
//   accelerating and its last braking.
// E_fixed: the main loop's X_k is within e = 2⁻¹⁶ + 2⁻¹² of X_k (√M's fraction by
//   ramp_math::sqrt_fraction_q16, h exact); s rounded to 2⁻¹⁶ shifts the interior by
//   k(n − k)/2·2⁻¹⁷ ≤ n²/8·2⁻¹⁷, d rounded by k·2⁻¹⁷; A_0 is the previous segment's A_n (off X by
//   ≤ n·2⁻¹⁷ + e, weighted ≤ 1 inside the segment), or the last exact step's X (e), the mid and
//   end points off by e (weights ≤ 1.25 together). For n ≤ 256: E_fixed ≤ 0.0625 + 0.002 +
//   0.0025 + 0.0006 < 0.07; with E_interp ≤ ⅜ and the planning errors above (< 0.01), every step
//   is within ½ + ⅜ + 0.08 < 0.96 tick of the ideal (the tests measure ≤ 0.87). ⅜ rather than ¼
//   (83) makes ≈ 13 % fewer segments (n ∝ E^⅓ at a given x) at the price of that margin.
// Range: d and s are 32-bit (d unsigned Q16.16 below 2¹⁶ − 1 ticks, s signed Q16.16); a segment
// whose intervals leave that range (slow steps, a huge first change) is not made: those steps
// are pushed one by one with their exact times, as is each phase's first step and a replacing
// move's first step. A segment also ends at its phase's end and within the ring's reach (the
// handover lead's worth of steps past what is pushed, step_scheduler.cpp), so n is the largest
// power of two under the bound, the phase and the lead.
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

// Ramp segments (see "Ramp segments" above).
inline constexpr uint32_t kMaxRampSegmentSteps = 256;
// The intervals a ramp segment may play (Q16.16 in 32 bits, and the accumulator's sum below 2³²).
inline constexpr uint32_t kMaxRampSegmentInterval = 0xFFFEu << 16;

// 124·x²·⌊√x⌋ for x = x_lo, saturated: a segment of n steps (a power of two ≥ 4) stays within ⅜
// tick of the quadratic it is played as when n³·κ is at most this at its smallest M
// (x_lo = ⌊M/K⌋ there, κ = ⌊√K⌋ + 1).
uint64_t ramp_segment_reach(uint64_t x_lo);
bool ramp_segment_fits(uint32_t n, uint64_t x_lo, uint32_t kappa);

// The interrupt's interval and add for a segment of n steps (a power of two ≥ 2) from the
// accumulator a0 through the ideal points x_mid (step n/2) and x_end (step n), all Q16 ticks
// from one reference; a_end: the accumulator after the segment. False when out of range.
struct RampSegment {
  uint32_t interval;  // Q16.16, the first step's
  int32_t add;        // Q16.16, per step
};
bool fit_ramp_segment(int64_t a0, int64_t x_mid, int64_t x_end, uint32_t n, RampSegment& out,
                      int64_t& a_end);

// Integer helpers (main-loop context; they divide).
namespace ramp_math {
uint32_t isqrt(uint64_t x);           // floor(√x)
uint64_t isqrt_q16(uint64_t x);       // floor(√x · 2¹⁶), x < 2⁶²
// floor(√x · 2¹⁶) from root = floor(√x) and rest = x − root² (no division).
uint64_t isqrt_q16_from(uint64_t root, uint64_t rest);
// The fraction √x − root in 2⁻¹⁶, floored (from root = floor(√x) < 2³⁰ and rest = x − root²):
// exact for root < 1024, else rest/(2·root + ½) (a 32-bit long division), within 1/(4·root)
// ≤ 2⁻¹² of the exact fraction before the floor.
uint32_t sqrt_fraction_q16(uint32_t root, uint32_t rest);
uint64_t mul_div(uint64_t a, uint64_t b, uint64_t c);  // floor(a·b/c); saturates at 2⁶⁴ − 1
}  // namespace ramp_math

}  // namespace hmc::fw
