// The main loop's integer math of ramp step times (step_scheduler.cpp): a widening multiply,
// the exact integer square root carried from one point to the next, the rounding test of a
// ramp step's time, and a left shift of a signed value.
//
// It runs per ramp step pushed alone and twice per ramp segment on a Cortex-M0+, which has a
// single-cycle 32×32→32 multiply and no divider: no division, no 64-bit multiply helper, no
// loop whose length grows with the numbers except the correction in settle_root, which takes
// two tests per bit of the guess's error (none or a few bits; see ramp.h).
#pragma once

#include <stdint.h>

namespace hmc::fw::step_math {

// a·b exactly, from four 16×16 products: the M0+ has no 32×32→64 multiply instruction, and a
// plain 64-bit product would call __aeabi_lmul.
inline uint64_t mul_u32(uint32_t a, uint32_t b) {
  const uint32_t a_lo = a & 0xFFFFu;
  const uint32_t a_hi = a >> 16;
  const uint32_t b_lo = b & 0xFFFFu;
  const uint32_t b_hi = b >> 16;
  const uint64_t middle = uint64_t{a_lo * b_hi} + uint64_t{a_hi * b_lo};
  return (uint64_t{a_hi * b_hi} << 32) + (middle << 16) + uint64_t{a_lo * b_lo};
}

// Turns a guess `root` of floor(√m) into the exact value. On entry `rest` is m − root² (negative
// when the guess is too high); on exit root = floor(√m) and rest = m − root², so 0 ≤ rest ≤ 2·root.
// Gallops away from the guess by doubling strides, then halves the stride back: each pass keeps
// p = 2·root·stride and q = stride², so moving the root by a stride changes rest by p ± q.
// Rest is the signed type of `rest`, Wide the unsigned type of p and q.
template <typename Rest, typename Wide>
inline void settle_root_in(uint64_t m, uint32_t& root, Rest& rest) {
  uint32_t stride = 1;
  Wide p = Wide{root} << 1;
  Wide q = 1;
  if (rest < 0) {
    // Too high: step down until (root − stride)² ≤ m; the root then lies in [root, root + stride).
    for (;;) {
      if (stride > root) {  // would pass zero: the root lies in [0, stride)
        root = 0;
        rest = static_cast<Rest>(m);
        p = 0;
        break;
      }
      const Rest lower = rest + static_cast<Rest>(p - q);
      root -= stride;
      rest = lower;
      p -= q << 1;
      if (lower >= 0) break;
      stride <<= 1;
      p <<= 1;
      q <<= 2;
    }
  } else {
    // Not too high: step up while (root + stride)² ≤ m; the root then lies in [root, root + stride).
    while (static_cast<Wide>(rest) >= p + q) {
      rest -= static_cast<Rest>(p + q);
      root += stride;
      p += q << 1;
      stride <<= 1;
      p <<= 1;
      q <<= 2;
    }
  }
  // From here rest ≥ 0.
  while (stride > 1) {
    stride >>= 1;
    p >>= 1;
    q >>= 2;
    if (static_cast<Wide>(rest) >= p + q) {
      rest -= static_cast<Rest>(p + q);
      root += stride;
      p += q << 1;
    }
  }
}

// settle_root_in over the widths the guess needs: 32-bit when root < 2²⁴ and |rest| < 2²⁸
// (the main loop's usual case: its guesses are a few ticks off). There the root moves by at most
// |rest|/root (≤ 2¹⁴ when small), so p = 2·root·stride ≤ 4·|rest| + 2·root and q = stride² stay
// below 2³¹, and m itself is below 2³⁰ when the root passes zero.
inline void settle_root(uint64_t m, uint32_t& root, int64_t& rest) {
  constexpr int64_t kNarrow = int64_t{1} << 28;
  if (root < (uint32_t{1} << 24) && rest > -kNarrow && rest < kNarrow) {
    auto narrow = static_cast<int32_t>(rest);
    settle_root_in<int32_t, uint32_t>(m, root, narrow);
    rest = narrow;
    return;
  }
  settle_root_in<int64_t, uint64_t>(m, root, rest);
}

// v·2^s for either sign (a left shift of a negative value is undefined before C++20), s < 64.
inline int64_t shl(int64_t v, uint32_t s) {
  return static_cast<int64_t>(static_cast<uint64_t>(v) << s);
}

// Whether √m + h reaches root + 1, given root = floor(√m), rest = m − root² and
// g = 1 − h in units of 2⁻¹⁶ (1..65535): √m ≥ root + g ⇔ rest ≥ 2·root·g + g². Exact in 64 bits
// for root < 2³⁰.
inline bool rounds_up(uint32_t root, int64_t rest, uint32_t g) {
  const uint64_t lhs = static_cast<uint64_t>(rest) << 32;
  const uint64_t rhs = (mul_u32(root, g) << 17) + uint64_t{g * g};
  return lhs >= rhs;
}

}  // namespace hmc::fw::step_math
