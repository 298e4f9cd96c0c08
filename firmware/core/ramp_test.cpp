// Unit tests of the ramp math: the interrupt's integer helpers (step_math.h) against plain
// 64-bit and long double arithmetic, and the planner's phase counts.
#include "core/ramp.h"

#include <catch2/catch.hpp>

#include <stdint.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/step_math.h"

using hmc::fw::kEndless;
using hmc::fw::MoveSpec;
using hmc::fw::Phase;
using hmc::fw::PhaseKind;
using hmc::fw::plan_move;
using hmc::fw::plan_stop;
using hmc::fw::PlanStatus;
using hmc::fw::Profile;
namespace rm = hmc::fw::ramp_math;
namespace sm = hmc::fw::step_math;

namespace {

__extension__ typedef unsigned __int128 U128;

uint32_t reference_isqrt(uint64_t x) {
  auto root = static_cast<uint64_t>(std::sqrt(static_cast<long double>(x)));
  while (root * root > x) --root;
  while ((root + 1) * (root + 1) <= x) ++root;
  return static_cast<uint32_t>(root);
}

uint32_t phase_total(const Profile& profile) {
  uint32_t total = 0;
  for (uint8_t i = 0; i < profile.phase_count; ++i) total += profile.phases[i].steps;
  return total;
}

}  // namespace

TEST_CASE("mul_u32 is the exact 64-bit product") {
  std::mt19937_64 rng(1);
  const uint32_t edges[] = {0, 1, 0xFFFF, 0x10000, 0x7FFFFFFF, 0x80000000u, 0xFFFFFFFFu};
  for (uint32_t a : edges) {
    for (uint32_t b : edges) CHECK(sm::mul_u32(a, b) == uint64_t{a} * b);
  }
  for (int i = 0; i < 100000; ++i) {
    const auto a = static_cast<uint32_t>(rng());
    const auto b = static_cast<uint32_t>(rng());
    REQUIRE(sm::mul_u32(a, b) == uint64_t{a} * b);
  }
}

TEST_CASE("settle_root finds floor(sqrt) from any guess") {
  std::mt19937_64 rng(2);
  for (int i = 0; i < 200000; ++i) {
    const uint64_t m = rng() >> (4 + rng() % 60);  // below 2^60, all magnitudes
    const uint32_t exact = reference_isqrt(m);
    uint32_t guess = 0;
    switch (i % 4) {
      case 0: guess = exact; break;
      case 1: guess = exact + static_cast<uint32_t>(rng() % 3); break;
      case 2: guess = exact > 0 ? exact - static_cast<uint32_t>(rng() % (exact + 1ull)) : 0; break;
      default: guess = static_cast<uint32_t>(rng() % (2ull * exact + 2)); break;
    }
    int64_t rest = static_cast<int64_t>(m) - static_cast<int64_t>(uint64_t{guess} * guess);
    uint32_t root = guess;
    sm::settle_root(m, root, rest);
    REQUIRE(root == exact);
    REQUIRE(rest == static_cast<int64_t>(m - uint64_t{exact} * exact));
  }
}

TEST_CASE("settle_root's 32-bit path: roots below 2^24, guesses whose rest is within 2^28") {
  std::mt19937_64 rng(12);
  for (int i = 0; i < 200000; ++i) {
    const auto exact = static_cast<uint32_t>(rng() % (uint64_t{1} << (1 + rng() % 24)));
    const uint64_t m = uint64_t{exact} * exact + rng() % (2ull * exact + 1);
    // A guess whose rest lies within the narrow window, up to its edges.
    const int64_t window = int64_t{1} << (rng() % 29);
    int64_t rest = 0;
    uint32_t guess = exact;
    const int64_t stride = static_cast<int64_t>(rng() % 4096);
    for (int64_t g = exact + (i % 2 == 0 ? stride : -stride); ; g += (i % 2 == 0 ? -1 : 1)) {
      if (g < 0 || g >= (int64_t{1} << 24)) continue;
      rest = static_cast<int64_t>(m) - g * g;
      if (g == exact || (rest > -window && rest < window)) {
        guess = static_cast<uint32_t>(g);
        break;
      }
    }
    uint32_t root = guess;
    sm::settle_root(m, root, rest);
    REQUIRE(root == reference_isqrt(m));
    REQUIRE(rest == static_cast<int64_t>(m - uint64_t{root} * root));
  }
}

TEST_CASE("rounds_up decides floor(sqrt(m) + h)") {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100000; ++i) {
    const uint64_t m = rng() >> (4 + rng() % 58);
    const uint32_t root = reference_isqrt(m);
    const auto g = static_cast<uint32_t>(1 + rng() % 65535);
    const long double x = std::sqrt(static_cast<long double>(m));
    const long double h = 1.0L - static_cast<long double>(g) / 65536.0L;
    const int64_t rest = static_cast<int64_t>(m - uint64_t{root} * root);
    const bool up = sm::rounds_up(root, rest, g);
    const long double target = static_cast<long double>(root) + 1.0L - h;
    if (std::fabs(x - target) < 1e-9L) continue;  // a tie the long double cannot call
    REQUIRE(up == (x + h >= static_cast<long double>(root) + 1.0L));
  }
}

TEST_CASE("isqrt, isqrt_q16 and mul_div") {
  std::mt19937_64 rng(4);
  CHECK(rm::isqrt(0) == 0);
  CHECK(rm::isqrt(~uint64_t{0}) == 0xFFFFFFFFu);
  CHECK(rm::isqrt_q16(2) == 92681);  // √2 · 65536 = 92681.9
  CHECK(rm::mul_div(~uint64_t{0}, ~uint64_t{0}, ~uint64_t{0}) == ~uint64_t{0});
  CHECK(rm::mul_div(uint64_t{1} << 63, 4, 8) == uint64_t{1} << 62);
  CHECK(rm::mul_div(uint64_t{1} << 63, 4, 1) == ~uint64_t{0});  // saturates
  for (int i = 0; i < 20000; ++i) {
    const uint64_t x = rng() >> (2 + rng() % 60);
    REQUIRE(rm::isqrt(x) == reference_isqrt(x));
    const uint64_t q = rm::isqrt_q16(x);
    const long double exact = std::sqrt(static_cast<long double>(x)) * 65536.0L;
    REQUIRE(static_cast<long double>(q) <= exact + 1e-6L);
    REQUIRE(static_cast<long double>(q) + 1.0L > exact - 1e-6L);
    const uint64_t a = rng(), b = rng() >> (rng() % 64), c = (rng() >> (rng() % 64)) | 1;
    const U128 p = static_cast<U128>(a) * b / c;
    const uint64_t expected = p >> 64 ? ~uint64_t{0} : static_cast<uint64_t>(p);
    REQUIRE(rm::mul_div(a, b, c) == expected);
  }
}

TEST_CASE("sqrt_fraction_q16 is within 2^-16 + 1/(4 root) of the fraction, exact below 1024") {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 200000; ++i) {
    const uint64_t m = rng() >> (4 + rng() % 60);  // below 2^60
    const uint32_t root = reference_isqrt(m);
    const auto rest = static_cast<uint32_t>(m - uint64_t{root} * root);
    const uint32_t fraction = rm::sqrt_fraction_q16(root, rest);
    if (root < 1024) {
      REQUIRE(fraction == rm::isqrt_q16(m) - (uint64_t{root} << 16));
      continue;
    }
    const long double exact = (std::sqrt(static_cast<long double>(m)) - root) * 65536.0L;
    const long double bound = 1.0L + 65536.0L / (4.0L * root);
    REQUIRE(std::fabs(static_cast<long double>(fraction) - exact) <= bound);
  }
}

TEST_CASE("plans split every move into phases that add up to it") {
  std::mt19937_64 rng(5);
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    MoveSpec spec{};
    spec.microstep = static_cast<uint16_t>(1u << (rng() % 9));
    spec.steps = static_cast<uint32_t>(rng() % 5 == 0 ? 0 : 1 + rng() % 100000);
    spec.interval = static_cast<uint32_t>(240 + rng() % 200000);
    spec.accel = static_cast<uint32_t>(1 + rng() % 2000000);
    Profile profile{};
    const uint64_t entry = rng() % 3 == 0 ? 0 : rng() >> (8 + rng() % 40);
    const PlanStatus status = plan_move(spec, entry, profile);
    if (status != PlanStatus::kOk) {
      CHECK(status == PlanStatus::kRampTooLong);
      continue;
    }
    ++checked;
    REQUIRE(profile.phase_count >= 1);
    REQUIRE(profile.phase_count <= 3);
    const Phase& last = profile.phases[profile.phase_count - 1];
    if (spec.steps == 0) {
      REQUIRE(profile.endless);
      REQUIRE(last.kind == PhaseKind::kCruise);
      REQUIRE(last.steps == kEndless);
    } else {
      REQUIRE(last.kind == PhaseKind::kDown);
      REQUIRE(phase_total(profile) == profile.total_steps);
      // Exact count, unless the move is shorter than the distance needed to stop from its entry.
      if (uint64_t{spec.steps} * profile.k >= entry) REQUIRE(profile.total_steps == spec.steps);
      // Braking ends at rest: M runs down to exactly 0 at a move's last step.
      if (profile.total_steps == spec.steps) REQUIRE(last.m == uint64_t{last.steps} * profile.k);
    }
    for (uint8_t p = 0; p < profile.phase_count; ++p) {
      const Phase& phase = profile.phases[p];
      if (phase.kind == PhaseKind::kDown) REQUIRE(phase.m >= uint64_t{phase.steps} * profile.k);
      if (phase.kind != PhaseKind::kCruise) REQUIRE(phase.root == reference_isqrt(phase.m));
    }
  }
  CHECK(checked > 10000);
}

TEST_CASE("plans refuse what they cannot do") {
  Profile profile{};
  CHECK(plan_move({false, 3, 10, 4800, 0}, 0, profile) == PlanStatus::kBadMicrostep);
  CHECK(plan_move({false, 512, 10, 4800, 0}, 0, profile) == PlanStatus::kBadMicrostep);
  CHECK(plan_move({false, 0, 10, 4800, 0}, 0, profile) == PlanStatus::kBadMicrostep);
  CHECK(plan_move({false, 1, 10, 239, 0}, 0, profile) == PlanStatus::kIntervalShort);
  CHECK(plan_move({false, 1, 10, 240, 0}, 0, profile) == PlanStatus::kOk);
  CHECK(plan_move({false, 1, 10, 4800, 0x80000000u}, 0, profile) == PlanStatus::kBadAccel);
  // 1 step/s² up to 10 000 steps/s would take 10 000 s.
  CHECK(plan_move({false, 1, 10, 4800, 1}, 0, profile) == PlanStatus::kRampTooLong);
  CHECK(plan_stop({false, 1, 10, 4800, 1000}, uint64_t{1} << 61, profile) ==
        PlanStatus::kRampTooLong);
}

TEST_CASE("a stop brakes over floor(M/K) steps") {
  Profile profile{};
  const MoveSpec spec{false, 1, 0, 4800, 1000};
  const uint64_t k = 2 * 48000000ull * 48000000ull / 1000;
  REQUIRE(plan_stop(spec, 7 * k + 5, profile) == PlanStatus::kOk);
  CHECK(profile.stopping);
  CHECK(profile.total_steps == 7);
  CHECK(profile.phases[0].kind == PhaseKind::kDown);
  REQUIRE(plan_stop(spec, k - 1, profile) == PlanStatus::kOk);
  CHECK(profile.total_steps == 0);
  CHECK(profile.phase_count == 0);
}

namespace {

// A ramp segment of n steps of f(j) = ±√((x0 ± j)·K) (accelerating: +, from step x0; braking:
// −, toward rest), fitted by fit_ramp_segment and played as the interrupt does (step_engine.h,
// ramp_step: A += d, d += s): the largest |A_j − f(j)| in ticks over the segment; -1 when the
// segment is out of the interrupt's range.
long double segment_error(uint64_t k, uint64_t x0, uint32_t n, bool braking) {
  const auto x_q16 = [&](uint64_t j) {
    const uint64_t m = (braking ? x0 - j : x0 + j) * k;
    const auto root = static_cast<int64_t>(rm::isqrt_q16(m));
    return braking ? (int64_t{1} << 50) - root : root;
  };
  const int64_t a0 = x_q16(0);
  hmc::fw::RampSegment seg{};
  int64_t a_end = 0;
  if (!hmc::fw::fit_ramp_segment(a0, x_q16(n / 2), x_q16(n), n, seg, a_end)) return -1.0L;
  int64_t acc = a0;
  int64_t interval = seg.interval;
  long double worst = 0;
  for (uint32_t j = 1; j <= n; ++j) {
    acc += interval;
    interval += seg.add;
    const long double m = static_cast<long double>(braking ? x0 - j : x0 + j) * k;
    const long double ideal = braking ? static_cast<long double>(int64_t{1} << 34) - std::sqrt(m)
                                      : std::sqrt(m);
    worst = std::max(worst, std::fabs(static_cast<long double>(acc) / 65536.0L - ideal));
  }
  REQUIRE(acc == a_end);  // the main loop's copy of the accumulator is exact
  return worst;
}

// The longest segment ramp_segment_fits allows from step x0 (n = 2 always: no interpolation).
uint32_t allowed_steps(uint64_t k, uint64_t x0, bool braking) {
  const uint32_t kappa = rm::isqrt(k) + 1;
  uint32_t n = hmc::fw::kMaxRampSegmentSteps;
  while (n > 2 && !(braking ? x0 >= n && hmc::fw::ramp_segment_fits(n, x0 - n, kappa)
                            : hmc::fw::ramp_segment_fits(n, x0, kappa))) {
    n >>= 1;
  }
  return n;
}

uint64_t k_of(uint64_t accel) { return (2 * 48000000ull * 48000000ull + accel / 2) / accel; }

}  // namespace

TEST_CASE("ramp segments the bound allows stay within 3/8 tick and a bit of the ideal") {
  std::mt19937_64 rng(6);
  int played = 0;
  long double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const uint64_t accel = 100 + rng() % 0x7FFFFF9Bu;
    const uint64_t k = k_of(accel);
    const uint64_t x0 = 2 + (rng() >> (rng() % 64)) % (uint64_t{1} << 24);
    const bool braking = (i & 1) != 0;
    if ((x0 + 600) * k >= (uint64_t{1} << 60)) continue;
    const uint32_t n = allowed_steps(k, x0, braking);
    if (braking && x0 < n) continue;
    const long double error = segment_error(k, x0, n, braking);
    if (error < 0) continue;  // intervals beyond the interrupt's range: pushed one by one
    ++played;
    worst = std::max(worst, error);
    REQUIRE(error <= 0.375L + 0.07L);
  }
  CHECK(played > 5000);
  std::printf("  ramp segments the bound allows (%d)           worst |A - X| %.4Lf ticks\n",
              played, worst);
}

TEST_CASE("a ramp segment twice as long as the bound allows leaves the one-tick budget") {
  // Where the rule stops at n (n < 256), 2n steps played as one segment stray by more than the
  // half tick the rounding leaves: the bound is what keeps every step within one tick.
  long double worst = 0;
  for (const uint64_t accel : {1000ull, 20000ull, 500000ull, 2000000000ull}) {
    const uint64_t k = k_of(accel);
    for (uint64_t x0 = 4; x0 < (uint64_t{1} << 22); x0 += x0 / 8 + 1) {
      for (const bool braking : {false, true}) {
        const uint32_t n = allowed_steps(k, x0, braking);
        // Far from rest (x0 ≥ 32n), where the third derivative barely changes over a segment and
        // the bound is close to the error itself.
        if (n >= hmc::fw::kMaxRampSegmentSteps || x0 < 32 * n) continue;
        const long double error = segment_error(k, x0, 2 * n, braking);
        worst = std::max(worst, error);
      }
    }
  }
  std::printf("  ramp segments one power of two too long      worst |A - X| %.4Lf ticks\n", worst);
  CHECK(worst > 0.5L);
}
