// Ramp planning (main-loop context): the ideal profile of ramp.h cut into integer phases.
// Reals are carried as signed 64-bit ticks with 16 fractional bits ("Q16").
#include "ramp.h"

#include "step_math.h"

namespace hmc::fw {
namespace ramp_math {

uint32_t isqrt(uint64_t x) {
  uint64_t root = 0;
  uint64_t bit = uint64_t{1} << 62;
  while (bit > x) bit >>= 2;
  while (bit != 0) {
    if (x >= root + bit) {
      x -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
    }
    bit >>= 2;
  }
  return static_cast<uint32_t>(root);
}

uint64_t isqrt_q16(uint64_t x) {
  const uint64_t root = isqrt(x);
  return isqrt_q16_from(root, x - root * root);
}

uint64_t isqrt_q16_from(uint64_t root, uint64_t rest) {
  // rest ≤ 2·root: stays below 2⁵⁰ over the 16 extra bits
  for (int bit = 0; bit < 16; ++bit) {
    rest <<= 2;
    root <<= 1;
    const uint64_t trial = (root << 1) + 1;  // (root + 1)² − root² after doubling
    if (rest >= trial) {
      rest -= trial;
      root += 1;
    }
  }
  return root;
}

uint32_t sqrt_fraction_q16(uint32_t root, uint32_t rest) {
  if (root < 1024) {
    return static_cast<uint32_t>(isqrt_q16_from(root, rest) - (uint64_t{root} << 16));
  }
  // √x − root = rest/(root + √x), root + √x within ½ of 2·root + ½: 16 quotient bits of
  // 2·rest/(4·root + 1), the remainder kept below the divisor (no 33rd bit).
  const uint32_t divisor = 4 * root + 1;
  uint32_t rem = 2 * rest;  // ≤ 4·root < divisor
  uint32_t quotient = 0;
  if (divisor < (uint32_t{1} << 31)) {  // the doubled remainder fits: plain long division
#pragma GCC unroll 16
    for (int bit = 0; bit < 16; ++bit) {
      rem <<= 1;
      quotient <<= 1;
      if (rem >= divisor) {
        rem -= divisor;
        quotient |= 1;
      }
    }
    return quotient;
  }
  for (int bit = 0; bit < 16; ++bit) {
    quotient <<= 1;
    if (rem >= divisor - rem) {
      rem -= divisor - rem;
      quotient |= 1;
    } else {
      rem <<= 1;
    }
  }
  return quotient;
}

uint64_t mul_div(uint64_t a, uint64_t b, uint64_t c) {
  constexpr uint64_t kLow = 0xFFFFFFFFu;
  const uint64_t ll = (a & kLow) * (b & kLow);
  const uint64_t lh = (a & kLow) * (b >> 32);
  const uint64_t hl = (a >> 32) * (b & kLow);
  const uint64_t hh = (a >> 32) * (b >> 32);
  const uint64_t middle = (ll >> 32) + (lh & kLow) + (hl & kLow);
  uint64_t low = (ll & kLow) | (middle << 32);
  uint64_t high = hh + (lh >> 32) + (hl >> 32) + (middle >> 32);
  if (high == 0) return low / c;
  if (high >= c) return ~uint64_t{0};
  // Long division of high:low by c, one quotient bit at a time; high stays below c.
  uint64_t quotient = 0;
  for (int bit = 0; bit < 64; ++bit) {
    const bool carry = (high >> 63) != 0;
    high = (high << 1) | (low >> 63);
    low <<= 1;
    quotient <<= 1;
    if (carry || high >= c) {
      high -= c;
      quotient |= 1;
    }
  }
  return quotient;
}

}  // namespace ramp_math

namespace {

using ramp_math::isqrt;
using ramp_math::isqrt_q16;
using ramp_math::mul_div;

constexpr uint64_t kF2 = kStepTicksPerSecond * kStepTicksPerSecond;  // 2.304·10¹⁵
constexpr int64_t kOne = 65536;                                     // 1.0 in Q16
constexpr int64_t kHalf = kOne / 2;
constexpr uint64_t kMaxTauQ16 = kMaxRampTicks << 16;
constexpr uint64_t kMaxM = kMaxRampTicks * kMaxRampTicks;
constexpr uint32_t kMaxAccel = 0x7FFFFFFFu;

// floor(v / 2¹⁶) for either sign.
int64_t floor_q16(int64_t v) { return v >= 0 ? v / kOne : -((-v + kOne - 1) / kOne); }

// Whole ticks nearest to a Q16 value.
int64_t round_q16(int64_t v) { return floor_q16(v + kHalf); }

int64_t q16(uint64_t ticks) { return static_cast<int64_t>(ticks) * kOne; }

// Whether n·k ≥ x, without forming n·k.
bool reaches(uint32_t n, uint64_t k, uint64_t x) { return n >= (x + k - 1) / k; }

// A phase of steps at base + floor(√M + h), M rising by k from m0; base is the ideal time
// offset (Q16) of the real ramp origin, so the step lands at the nearest tick.
void set_up(Phase& phase, uint32_t steps, uint64_t m0, uint64_t k, int64_t base_q16) {
  phase = Phase{};
  phase.kind = PhaseKind::kUp;
  phase.steps = steps;
  phase.m = m0;
  phase.root = isqrt(m0);
  phase.root_step = isqrt(m0 + k) - phase.root;
  const int64_t y = base_q16 + kHalf;  // round(base + √M) = floor(√M + y)
  phase.offset = floor_q16(y);
  phase.h = static_cast<uint16_t>(y - phase.offset * kOne);
}

// A phase of steps at base − floor(√M + h), M falling by k from m0. round(c − √M) with
// y = c + ½ = Y + f is Y − floor(√M + 1 − f) for f > 0, Y − 1 − floor(√M) for f = 0.
void set_down(Phase& phase, uint32_t steps, uint64_t m0, uint64_t k, int64_t base_q16,
              bool from_last_step) {
  phase = Phase{};
  phase.kind = PhaseKind::kDown;
  phase.from_last_step = from_last_step;
  phase.steps = steps;
  phase.m = m0;
  phase.root = isqrt(m0);
  phase.root_step = (steps > 0 && m0 >= k) ? phase.root - isqrt(m0 - k) : 0;
  const int64_t y = base_q16 + kHalf;
  const int64_t whole = floor_q16(y);
  const int64_t fraction = y - whole * kOne;
  phase.offset = fraction == 0 ? whole - 1 : whole;
  phase.h = static_cast<uint16_t>(fraction == 0 ? 0 : kOne - fraction);
}

void set_cruise(Phase& phase, uint32_t steps, uint32_t interval, int64_t first_offset) {
  phase = Phase{};
  phase.kind = PhaseKind::kCruise;
  phase.steps = steps;
  phase.interval = interval;
  phase.offset = first_offset;
}

bool is_microstep(uint16_t microstep) {
  return microstep != 0 && microstep <= 256 && (microstep & (microstep - 1)) == 0;
}

// T_v in Q16 for `interval` ticks per step of `from_microstep` steps, seen as steps of
// `to.microstep` at `to.accel`. Zero when out of range.
uint64_t velocity_time_q16(uint32_t interval, uint16_t from_microstep, const MoveSpec& to) {
  const uint64_t tv = mul_div(kF2, uint64_t{1} << 16, uint64_t{to.accel} * interval);
  return mul_div(tv, to.microstep, from_microstep);
}

void begin(const MoveSpec& spec, uint64_t m_entry, Profile& out) {
  out = Profile{};
  out.spec = spec;
  const int16_t units = static_cast<int16_t>(256 / spec.microstep);
  out.position_step = spec.reverse ? static_cast<int16_t>(-units) : units;
  out.m_entry = m_entry;
}

}  // namespace

uint64_t ramp_segment_reach(uint64_t x_lo) {
  // Beyond 2²⁰ steps from rest every n ≤ 256 fits: n³·κ < 2²⁴·2²⁷ ≤ 124·2⁵⁰.
  if (x_lo >= (uint64_t{1} << 20)) return ~uint64_t{0};
  // 32-bit from here: x < 2²⁰, x·⌊√x⌋ < 2³⁰.
  const auto x = static_cast<uint32_t>(x_lo);
  uint32_t rest = x;
  uint32_t root = 0;
  uint32_t bit = uint32_t{1} << 20;
  while (bit > rest) bit >>= 2;
  while (bit != 0) {
    if (rest >= root + bit) {
      rest -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
    }
    bit >>= 2;
  }
  return step_math::mul_u32(x * root, 124 * x);  // 124·x < 2²⁷: no 64-bit multiply
}

bool ramp_segment_fits(uint32_t n, uint64_t x_lo, uint32_t kappa) {
  return step_math::mul_u32(n * n * n, kappa) <= ramp_segment_reach(x_lo);
}

bool fit_ramp_segment(int64_t a0, int64_t x_mid, int64_t x_end, uint32_t n, RampSegment& out,
                      int64_t& a_end) {
  uint32_t shift = 0;  // m = n/2 = 2^shift
  while ((uint32_t{2} << shift) < n) ++shift;
  const int64_t to_mid = x_mid - a0;
  const int64_t to_end = x_end - a0;
  // s = (Δ_n − 2Δ_m)/m², rounded to the nearest (an arithmetic shift floors).
  const int64_t m2 = int64_t{1} << (2 * shift);
  const int64_t add = (to_end - 2 * to_mid + m2 / 2) >> (2 * shift);
  // n(n − 1)/2·s = ((s·n) − s)·m, products by powers of two as shifts (a 64-bit multiply is a
  // library call on the M0+).
  using step_math::shl;
  const int64_t pairs_add = shl(shl(add, shift + 1) - add, shift);
  const int64_t interval = (to_end - pairs_add + static_cast<int64_t>(n / 2)) >> (shift + 1);
  const int64_t last = interval + shl(add, shift + 1) - add;
  if (add < INT32_MIN || add > INT32_MAX) return false;
  if (interval < 0 || interval > kMaxRampSegmentInterval) return false;
  if (last < 0 || last > kMaxRampSegmentInterval) return false;
  out.interval = static_cast<uint32_t>(interval);
  out.add = static_cast<int32_t>(add);
  a_end = a0 + shl(interval, shift + 1) + pairs_add;
  return true;
}

PlanStatus check_move(const MoveSpec& spec) {
  if (!is_microstep(spec.microstep)) return PlanStatus::kBadMicrostep;
  if (spec.interval < kMinIntervalTicks) return PlanStatus::kIntervalShort;
  if (spec.accel > kMaxAccel) return PlanStatus::kBadAccel;
  return PlanStatus::kOk;
}

PlanStatus plan_move(const MoveSpec& spec, uint64_t m_entry, Profile& out) {
  const PlanStatus status = check_move(spec);
  if (status != PlanStatus::kOk) return status;
  begin(spec, m_entry, out);
  const uint32_t n = spec.steps;
  const uint32_t interval = spec.interval;
  out.total_steps = n;
  out.endless = n == 0;
  if (spec.accel == 0) {
    set_cruise(out.phases[0], n == 0 ? kEndless : n, interval, interval);
    out.phase_count = 1;
    return PlanStatus::kOk;
  }

  const uint64_t k = (2 * kF2 + spec.accel / 2) / spec.accel;
  const uint64_t tv_q16 = velocity_time_q16(interval, spec.microstep, spec);
  if (tv_q16 > kMaxTauQ16 || m_entry > kMaxM) return PlanStatus::kRampTooLong;
  const uint64_t m_v = mul_div(tv_q16, tv_q16, uint64_t{1} << 32);
  const int64_t tv = static_cast<int64_t>(tv_q16);
  const int64_t tu = static_cast<int64_t>(isqrt_q16(m_entry));
  out.k = k;
  out.m_cruise = m_v;

  if (n != 0 && !reaches(n, k, m_entry)) {
    // Too short to stop at the target: brake at a to rest, past it.
    const uint32_t steps = static_cast<uint32_t>(m_entry / k);
    set_down(out.phases[0], steps, m_entry, k, tu, false);
    out.phase_count = 1;
    out.total_steps = steps;
    out.endless = false;
    return PlanStatus::kOk;
  }

  // Phase 1: change speed from the entry speed toward v.
  const bool rising = m_entry <= m_v;
  uint32_t first = static_cast<uint32_t>((rising ? m_v - m_entry : m_entry - m_v) / k);
  const int64_t gap = rising ? tv - tu : tu - tv;  // |T_v − τ_u|, Q16
  uint8_t count = 0;

  if (n != 0 && rising && !reaches(n, k, 2 * m_v - m_entry)) {
    // Triangle: the peak comes before v.
    const uint64_t nk = uint64_t{n} * k;
    first = static_cast<uint32_t>((nk - m_entry) / (2 * k));
    const uint32_t last = n - first;
    if (first > 0) set_up(out.phases[count++], first, m_entry, k, -tu);
    const int64_t end = -tu + static_cast<int64_t>(isqrt_q16(2 * (nk + m_entry)));
    set_down(out.phases[count++], last, uint64_t{last} * k, k, end, false);
    out.phase_count = count;
    return PlanStatus::kOk;
  }

  if (n != 0) first = first < n ? first : n;
  if (first > 0) {
    if (rising) {
      set_up(out.phases[count++], first, m_entry, k, -tu);
    } else {
      set_down(out.phases[count++], first, m_entry, k, tu, false);
    }
  }
  // The cruise's first step, step first + 1: the speed change ends |T_v − τ_u| after the
  // anchor at x_v = |M_v − M_u|/K, then the motor covers first + 1 − x_v steps at v. (The
  // closed form (first + 1)·I ± (T_v − τ_u)²/(2T_v) cancels two terms of up to 10¹² ticks
  // when slowing to a very slow rate; this one stays within a few I.)
  const uint64_t m_first = rising ? m_entry + uint64_t{first} * k : m_entry - uint64_t{first} * k;
  const uint64_t short_of_v = rising ? m_v - m_first : m_first - m_v;  // < K
  const int64_t cruise_q16 =
      gap + q16(interval) - static_cast<int64_t>(mul_div(short_of_v, uint64_t{interval} << 16, k));
  const int64_t cruise_first = round_q16(cruise_q16);
  if (n == 0) {
    set_cruise(out.phases[count++], kEndless, interval, cruise_first);
    out.phase_count = count;
    return PlanStatus::kOk;
  }
  const uint64_t braking_max = m_v / k + 1;
  const uint32_t braking =
      static_cast<uint32_t>(braking_max < n - first ? braking_max : n - first);
  const uint32_t cruise = n - first - braking;
  if (cruise > 0) {
    set_cruise(out.phases[count++], cruise, interval, cruise_first);
    // From the last cruise step (scheduled at its ideal time rounded) to the end of braking.
    const int64_t end = q16(uint64_t{braking} * interval) + tv / 2 + cruise_q16 - cruise_first * kOne;
    set_down(out.phases[count++], braking, uint64_t{braking} * k, k, end, true);
  } else if (braking > 0) {
    // Braking ends where the cruise's step n would have come, plus T_v/2.
    const int64_t end = cruise_q16 + q16(uint64_t{braking - 1} * interval) + tv / 2;
    set_down(out.phases[count++], braking, uint64_t{braking} * k, k, end, false);
  }
  out.phase_count = count;
  return PlanStatus::kOk;
}

PlanStatus plan_stop(const MoveSpec& spec, uint64_t m_entry, Profile& out) {
  const PlanStatus status = check_move(spec);
  if (status != PlanStatus::kOk) return status;
  if (m_entry > kMaxM || spec.accel == 0) return PlanStatus::kRampTooLong;
  begin(spec, m_entry, out);
  const uint64_t k = (2 * kF2 + spec.accel / 2) / spec.accel;
  const uint32_t steps = static_cast<uint32_t>(m_entry / k);
  out.k = k;
  out.stopping = true;
  out.total_steps = steps;
  out.spec.steps = steps;
  if (steps > 0) {
    set_down(out.phases[0], steps, m_entry, k, static_cast<int64_t>(isqrt_q16(m_entry)), false);
    out.phase_count = 1;
  }
  return PlanStatus::kOk;
}

PlanStatus speed_at(const Profile& profile, uint32_t step, const MoveSpec& to, uint64_t& m_out) {
  m_out = 0;
  if (to.accel == 0 || !is_microstep(to.microstep)) return PlanStatus::kOk;
  const MoveSpec& from = profile.spec;
  bool cruising = profile.k == 0;
  bool found = step == 0;
  uint64_t m = profile.m_entry;
  for (uint8_t i = 0; i < profile.phase_count && !found && !cruising; ++i) {
    const Phase& phase = profile.phases[i];
    if (phase.kind != PhaseKind::kCruise && step <= phase.steps) {
      found = true;
      m = phase.kind == PhaseKind::kUp ? phase.m + uint64_t{step} * profile.k
                                       : phase.m - uint64_t{step} * profile.k;
    } else if (phase.kind == PhaseKind::kCruise && (phase.steps == kEndless || step <= phase.steps)) {
      cruising = true;
    } else {
      step -= phase.steps;
    }
  }
  if (cruising) {
    const uint64_t tv_q16 = velocity_time_q16(from.interval, from.microstep, to);
    if (tv_q16 > kMaxTauQ16) return PlanStatus::kRampTooLong;
    m_out = mul_div(tv_q16, tv_q16, uint64_t{1} << 32);
    return PlanStatus::kOk;
  }
  if (!found) return PlanStatus::kOk;  // past the end: at rest
  // Same position on the ramp means the same speed: M scales with 1/a and microstep².
  m = mul_div(m, from.accel, to.accel);
  m = mul_div(m, uint64_t{to.microstep} * to.microstep, uint64_t{from.microstep} * from.microstep);
  if (m > kMaxM) return PlanStatus::kRampTooLong;
  m_out = m;
  return PlanStatus::kOk;
}

}  // namespace hmc::fw
