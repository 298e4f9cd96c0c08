// Internal to the motion module (planning): ideal velocity profiles and their cutting into runs of
// whole steps at one rate. A trapezoid and an S-curve are piecewise constant jerk from rest to
// rest; the seed's staged ramp is generalised to N rates; an ideal profile is sampled into
// stages at equal times; and our firmware's own trapezoid is timed as the board runs it. Pure
// arithmetic: knows nothing of frames, links or files.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace hmc::motion::planning {

struct Segment {
  double t0, dur, x0, v0, a0, jerk;
  double x(double t) const { return x0 + v0 * t + a0 * t * t / 2 + jerk * t * t * t / 6; }
  double v(double t) const { return v0 + a0 * t + jerk * t * t / 2; }
};

class Ideal {
 public:
  void add(double dur, double a0, double jerk) {
    if (!(dur > 0)) return;
    const Segment s{t_, dur, x_, v_, a0, jerk};
    segments_.push_back(s);
    x_ = s.x(dur);
    v_ = s.v(dur);
    t_ += dur;
  }
  double duration() const { return t_; }
  const std::vector<Segment>& segments() const { return segments_; }

  double x(double t) const {
    for (const Segment& s : segments_) {
      if (t <= s.t0 + s.dur) return s.x(std::max(0.0, t - s.t0));
    }
    return x_;
  }
  double v(double t) const {
    for (const Segment& s : segments_) {
      if (t <= s.t0 + s.dur) return s.v(std::max(0.0, t - s.t0));
    }
    return 0;
  }
  // When the position reaches `pos` (positions never fall: bisection within its segment).
  double time_at(double pos) const {
    if (pos <= 0 || segments_.empty()) return 0;
    for (const Segment& s : segments_) {
      if (pos > s.x(s.dur)) continue;
      double lo = 0, hi = s.dur;
      for (int i = 0; i < 80; ++i) {
        const double mid = (lo + hi) / 2;
        (s.x(mid) < pos ? lo : hi) = mid;
      }
      return s.t0 + (lo + hi) / 2;
    }
    return t_;
  }

  double ramp_s = 0;  // when the first ramp reaches the peak speed

 private:
  std::vector<Segment> segments_;
  double t_ = 0, x_ = 0, v_ = 0;
};

// Constant acceleration up to v and down (a triangle when the distance is too short).
Ideal trapezoid(double distance, double v, double a);
// Jerk-limited: jerk up to the acceleration, hold it, jerk down to the peak speed; the mirror
// image to stop. Short moves lose the hold, then reach a lower peak.
Ideal s_curve(double distance, double v, double a, double j);

struct Slice {
  uint64_t steps;
  double rate;
};

// The seed's staged ramp generalised to N rates (see motion_plan.h).
std::vector<Slice> staged(uint64_t distance, double speed, double accel, uint32_t rates);
// An ideal profile cut into stages: the ramp at `slices` equal times, each stage the whole steps
// between two cuts at the mean rate of that stretch (so it takes as long as the ideal does);
// the speed-down mirrors the speed-up.
std::vector<Slice> sampled(const Ideal& p, uint64_t distance, int slices);
// Our firmware's trapezoid: the ideal profile with the board's own numbers (ramp.h): the rate is
// 10^6/delay exactly and the acceleration a whole number; the last step falls where it ends.
double firmware_ramp_s(uint64_t steps, uint32_t delay_us, uint32_t accel);

}  // namespace hmc::motion::planning
