// Ideal profiles and their stages (ramp_shapes.h).
#include "ramp_shapes.h"

#include <cmath>

namespace hmc::motion::planning {

// Constant acceleration up to v and down (a triangle when the distance is too short).
Ideal trapezoid(double distance, double v, double a) {
  Ideal p;
  if (distance <= 0) return p;
  const double ramp = v * v / (2 * a);
  const double peak = 2 * ramp <= distance ? v : std::sqrt(a * distance);
  p.ramp_s = peak / a;
  p.add(p.ramp_s, a, 0);
  if (peak == v) p.add((distance - 2 * ramp) / v, 0, 0);
  p.add(p.ramp_s, -a, 0);
  return p;
}

// Jerk-limited: jerk up to the acceleration, hold it, jerk down to the peak speed; the mirror
// image to stop. Short moves lose the hold, then reach a lower peak.
Ideal s_curve(double distance, double v, double a, double j) {
  Ideal p;
  if (distance <= 0) return p;
  struct Shape {
    double tj, ta, ap;
  };
  auto shape = [&](double peak) {
    if (peak * j >= a * a) return Shape{a / j, peak / a - a / j, a};
    const double tj = std::sqrt(peak / j);
    return Shape{tj, 0, j * tj};
  };
  // The speed-up ends at half the peak speed on average: it covers peak·time/2.
  auto ramp_distance = [&](double peak) {
    const Shape s = shape(peak);
    return peak * (2 * s.tj + s.ta) / 2;
  };
  double peak = v;
  if (2 * ramp_distance(v) > distance) {
    double lo = 0, hi = v;
    for (int i = 0; i < 200; ++i) {
      const double mid = (lo + hi) / 2;
      (2 * ramp_distance(mid) > distance ? hi : lo) = mid;
    }
    peak = lo;
  }
  const Shape s = shape(peak);
  p.ramp_s = 2 * s.tj + s.ta;
  p.add(s.tj, 0, j);
  p.add(s.ta, s.ap, 0);
  p.add(s.tj, s.ap, -j);
  p.add((distance - 2 * ramp_distance(peak)) / peak, 0, 0);
  p.add(s.tj, 0, -j);
  p.add(s.ta, -s.ap, 0);
  p.add(s.tj, -s.ap, j);
  return p;
}

// The seed's staged ramp generalised to N rates (see motion_plan.h).
std::vector<Slice> staged(uint64_t distance, double speed, double accel, uint32_t rates) {
  if (distance == 0) return {};
  const uint64_t of = std::max<uint32_t>(rates, 1);
  // Too short for one step per stage: only the lowest rates, as a short ramp never gets higher.
  const uint64_t n = distance < 2 * of - 1 ? (distance + 1) / 2 : of;
  auto rate = [&](uint64_t k) { return speed * static_cast<double>(k) / static_cast<double>(of); };

  std::vector<uint64_t> ramp;  // steps of ramp stages 1..n-1 (one side)
  for (uint64_t k = 1; k < n; ++k) {
    double steps = accel > 0 ? (rate(k) * rate(k) - rate(k - 1) * rate(k - 1)) / (2 * accel)
                             : static_cast<double>(distance) / (4.0 * static_cast<double>(of));
    ramp.push_back(std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(steps))));
  }
  // Each side may take at most (distance - 1) / 2 steps, leaving the top stage at least one.
  const uint64_t room = (distance - 1) / 2;
  uint64_t sum = 0;
  for (uint64_t s : ramp) sum += s;
  if (sum > room) {
    const double f = static_cast<double>(room) / static_cast<double>(sum);
    sum = 0;
    for (uint64_t& s : ramp) {
      s = std::max<uint64_t>(1, static_cast<uint64_t>(std::floor(static_cast<double>(s) * f)));
      sum += s;
    }
    while (sum > room) {
      --*std::max_element(ramp.begin(), ramp.end());
      --sum;
    }
  }
  std::vector<Slice> out;
  for (uint64_t k = 1; k < n; ++k) out.push_back({ramp[k - 1], rate(k)});
  out.push_back({distance - 2 * sum, rate(n)});
  for (uint64_t k = n - 1; k >= 1; --k) out.push_back({ramp[k - 1], rate(k)});
  return out;
}

// An ideal profile cut into stages: the ramp at `slices` equal times, each stage the whole steps
// between two cuts at the mean rate of that stretch (so it takes as long as the ideal does);
// the speed-down mirrors the speed-up.
std::vector<Slice> sampled(const Ideal& p, uint64_t distance, int slices) {
  std::vector<Slice> out;
  if (distance == 0) return out;
  const uint64_t half = distance / 2;
  std::vector<uint64_t> cuts;
  for (int i = 1; i <= slices; ++i) {
    const double x = p.x(p.ramp_s * i / slices);
    const uint64_t q = std::min(half, static_cast<uint64_t>(std::llround(std::max(0.0, x))));
    if (q > (cuts.empty() ? 0 : cuts.back())) cuts.push_back(q);
  }
  uint64_t prev = 0;
  double t_prev = 0;
  for (uint64_t q : cuts) {
    const double t = p.time_at(static_cast<double>(q));
    out.push_back({q - prev, static_cast<double>(q - prev) / (t - t_prev)});
    prev = q;
    t_prev = t;
  }
  const std::vector<Slice> up = out;
  if (distance - prev > prev) {
    const uint64_t steps = distance - 2 * prev;
    const double t = p.time_at(static_cast<double>(distance - prev));
    out.push_back({steps, static_cast<double>(steps) / (t - t_prev)});
  }
  out.insert(out.end(), up.rbegin(), up.rend());
  return out;
}

// Our firmware's trapezoid: the ideal profile with the board's own numbers (ramp.h): the rate is
// 10^6/delay exactly and the acceleration a whole number; the last step falls where it ends.
double firmware_ramp_s(uint64_t steps, uint32_t delay_us, uint32_t accel) {
  const double d = static_cast<double>(steps), v = 1e6 / delay_us, a = accel;
  return v * v / a <= d ? d / v + v / a : 2 * std::sqrt(d / a);
}

}  // namespace hmc::motion::planning
