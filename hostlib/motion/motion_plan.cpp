// Motion planning (motion_plan.h): a validated motion file turned into actions, STM stages and
// every motor's velocity over time. Profile shapes, their sampling into stages, the scaling of
// coordinated moves and the board's rate rules live here; plan_plot.cpp draws the result.
#include "hmc/motion_plan.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/session.h"

namespace hmc::motion {
namespace {

// ---------------------------------------------------------------------------------------
// The board's rules (docs/protocol.md, "What the board does") and the planner's choices

constexpr uint32_t kMinDelayUs = 5;
constexpr uint32_t kMaxDelayUs = 0xFFFFFFFFu / 48u;  // the 48 MHz step timer's 32-bit interval
constexpr uint32_t kMaxRate = proto::kSettings[proto::kSettingMaxRate - 1].max;  // per motor
constexpr uint32_t kBudget = 50000;         // all moving motors together
constexpr uint32_t kRampingBudget = 40000;  // ... while any of them ramps
constexpr uint32_t kMaxAccel = proto::kSettings[proto::kSettingAccel - 1].max;
constexpr double kMaxRampS = 1073741824.0 / 48e6;  // the firmware's longest ramp: 2^30 ticks
constexpr double kHomeEstimateS = 0.5;
constexpr double kFadeFrameS = 0.05;
constexpr int kTrapezoidSlices = 8;
constexpr int kSCurveSlices = 12;

// The rate the board counts for a delay (it rounds up).
uint32_t board_rate(uint32_t delay_us) { return (1000000u + delay_us - 1u) / delay_us; }

std::string num(double x) {
  char buf[48];
  if (std::fabs(x - std::round(x)) < 1e-6) {
    std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(std::llround(x)));
  } else {
    std::snprintf(buf, sizeof buf, "%.2f", x);
    std::string s = buf;
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
    return s;
  }
  return buf;
}

std::string signed_steps(int64_t steps) {
  return (steps >= 0 ? "+" : "") + std::to_string(steps) + " steps";
}

// Why one motor's move cannot be planned.
struct Problem {
  std::string expected, found, message;
};

// ---------------------------------------------------------------------------------------
// Ideal profiles: piecewise constant jerk, from rest to rest

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

// ---------------------------------------------------------------------------------------
// Stages: runs of whole steps at one rate

struct Slice {
  uint64_t steps;
  double rate;
};

struct Piece {
  uint64_t steps;
  uint32_t delay_us;
};

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

size_t chars(const Command& command) {
  const Result<std::string, Diagnostic> frame = encode(command);
  return frame.ok() ? frame.value().size() : 0;
}

// How a slowed motor's move is made to take a given time.
enum class Shape : uint8_t {
  kAsked,      // the file's profile
  kStaircase,  // a ramp the firmware cannot stretch far enough, sampled into stages instead
  kConstant,   // one rate: the last resort for very long stretches
};

struct Fit {
  double target_s = 0;
  Shape shape = Shape::kAsked;
  bool keep_first = false;  // adjust a stage other than the first (its line then keeps its length)
  size_t stm_chars = 0;     // when not 0: the first STM line must keep this length,
  size_t set_chars = 0;     //   and the SET accel line this one (so no other motor's start moves)
  double tolerance_s = 0;   // how far from target_s the move may end
};

// Coordinated motors must end within one step period of each other: each aims for the common
// end within half the shortest step period among them, and never needs to be closer than half
// a step at the board's fastest rate.
constexpr double kSyncToleranceS = 1.0 / kMaxRate;

// Makes the pieces take `target_us` to within half a microsecond: the longest (with keep_first,
// the longest but the first) is split into a run at delay d and one at d + 1 that fill the time
// the others leave.
void fit_duration(std::vector<Piece>& pieces, double target_us, bool keep_first) {
  const size_t from = keep_first && pieces.size() > 1 ? 1 : 0;
  if (pieces.size() <= from) return;
  size_t m = from;
  for (size_t i = from + 1; i < pieces.size(); ++i) {
    if (pieces[i].steps > pieces[m].steps) m = i;
  }
  double others = 0;
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (i != m) others += static_cast<double>(pieces[i].steps) * pieces[i].delay_us;
  }
  const uint64_t n = pieces[m].steps;
  const double need = target_us - others;
  const double mean = need / static_cast<double>(n);
  if (mean < kMinDelayUs || mean >= kMaxDelayUs) return;
  const auto d = static_cast<uint32_t>(std::floor(mean));
  const double extra = std::round(need - static_cast<double>(n) * d);
  const auto slow = static_cast<uint64_t>(std::clamp(extra, 0.0, static_cast<double>(n)));
  std::vector<Piece> split;
  if (n > slow) split.push_back({n - slow, d});
  if (slow > 0) split.push_back({slow, d + 1});
  pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(m));
  pieces.insert(pieces.begin() + static_cast<std::ptrdiff_t>(m), split.begin(), split.end());
}

struct FirmwareRamp {
  uint32_t delay_us = 0;
  uint32_t accel = 0;
};

// The delay and acceleration whose firmware trapezoid takes closest to `target_s`: never faster
// than v nor harder than `a_max`, within the board's limits, and accepted by `lines_ok`. Two
// searches: delays near 10^6/v, each with the accelerations that fit best, and accelerations
// near a, each with the delays that fit best (either alone may be too coarse).
template <typename LinesOk>
std::optional<FirmwareRamp> fit_ramp(uint64_t steps, double v, double a, double a_max, double target_s,
                                     const LinesOk& lines_ok) {
  const double d0 = std::max(std::ceil(1e6 / v - 1e-9), double{kMinDelayUs});
  const auto d_steps = static_cast<double>(steps);
  std::optional<FirmwareRamp> best;
  double best_err = 0;
  auto consider = [&](double d, double acc) {
    if (d < d0 || d > kMaxDelayUs || acc < 1 || acc > std::min(a_max, double{kMaxAccel})) return;
    const auto di = static_cast<uint32_t>(d);
    const auto ai = static_cast<uint32_t>(acc);
    if (board_rate(di) > kMaxRate || 1e6 / di / ai > kMaxRampS) return;
    const double err = std::fabs(firmware_ramp_s(steps, di, ai) - target_s);
    if ((!best || err < best_err) && lines_ok(di, ai)) {
      best = FirmwareRamp{di, ai};
      best_err = err;
    }
  };
  // Delays above kMaxDelayUs are never considered: stop there, or a very slow v (a huge d0,
  // where ++d may not even change d) keeps this loop going for ever.
  const double window = std::max(3.0, std::floor(d0 / 50));
  const double d_last = std::min(d0 + window, double{kMaxDelayUs});
  for (double d = d0; d <= d_last; ++d) {
    const double vv = 1e6 / d;
    const double guesses[2] = {4 * d_steps / (target_s * target_s),  // triangle
                               target_s > d_steps / vv ? vv / (target_s - d_steps / vv) : 0};
    for (double g : guesses) {
      consider(d, std::floor(g));
      consider(d, std::ceil(g));
    }
  }
  const double a0 = std::round(a);
  const double spread = std::max(50.0, std::floor(a0 / 20));
  for (double acc = std::max(1.0, a0 - spread); acc <= a0 + spread; ++acc) {
    // Trapezoid of duration T: v² - a·T·v + a·D = 0, the smaller root.
    const double disc = acc * acc * target_s * target_s - 4 * acc * d_steps;
    if (disc < 0) continue;
    const double vv = (acc * target_s - std::sqrt(disc)) / 2;
    if (!(vv > 0)) continue;
    const double d = 1e6 / vv;
    consider(std::floor(d), acc);
    consider(std::ceil(d), acc);
  }
  return best;
}

// One motor's part of a move.
// The time a line takes on the wire (10 bits a byte), 0 when the link has no baud rate.
double wire_s(size_t bytes, uint32_t baud) { return baud == 0 ? 0.0 : static_cast<double>(bytes) * 10.0 / baud; }

double wire_s(const Command& command, uint32_t baud) {
  const Result<std::string, Diagnostic> frame = encode(command);
  return frame.ok() ? wire_s(frame.value().size() + 1, baud) : 0.0;
}

// What the time between two stages of a motor depends on: the runner sends a stage once it knows
// the one before has ended.
struct LinkTiming {
  uint32_t baud = 0;
  TargetFirmware firmware = TargetFirmware::kV2;
  int64_t start_units = 0;  // where the move starts, 1/256 step (the end events' lengths)
};

// Our firmware: the end event goes out at the board's next main-loop pass, then crosses the
// wire, then the next stage's line does, and the board starts it at its next pass.
constexpr double kBoardLoopS = 100e-6;

struct MotorPlan {
  uint32_t motor = 1;
  uint32_t microstep = 16;
  uint32_t dir = proto::kActionForward;
  uint64_t steps = 0;
  std::vector<Piece> pieces;
  bool firmware_ramp = false;  // our firmware ramps: one STM at the top rate after SET accel
  uint32_t accel = 0;
  LinkTiming link;

  // The pause before piece i (i >= 1): with our firmware the end event's and the new line's
  // wire time and the board's main loop; with the seed's, the host's margin on the previous
  // piece's time (session.h) and the line.
  double gap_s(size_t i) const {
    const double line = wire_s(stm(i), link.baud);
    const Piece& before = pieces[i - 1];
    if (link.firmware == TargetFirmware::kSeed) {
      const double previous = static_cast<double>(before.steps) * before.delay_us / 1e6;
      return previous * (kSeedTimeMargin - 1.0) + std::chrono::duration<double>(kSeedTimeSlack).count() + line;
    }
    int64_t units = link.start_units;
    const int64_t per_step = 256 / static_cast<int64_t>(microstep);
    for (size_t k = 0; k < i; ++k) {
      units += (dir == proto::kActionForward ? 1 : -1) * static_cast<int64_t>(pieces[k].steps) * per_step;
    }
    const Result<std::string, Diagnostic> ended =
        encode_board_frame(BoardFrame{MotionEnded{motor, MotionEnd::kCompleted, units}});
    const double event = ended.ok() ? wire_s(ended.value().size() + 1, link.baud) : 0.0;
    return 2 * kBoardLoopS + event + line;
  }
  double gaps_s() const {
    double total = 0;
    for (size_t i = 1; i < pieces.size(); ++i) total += gap_s(i);
    return total;
  }
  double duration_s() const {
    if (firmware_ramp) return firmware_ramp_s(steps, pieces[0].delay_us, accel);
    double us = 0;
    for (const Piece& p : pieces) us += static_cast<double>(p.steps) * p.delay_us;
    return us / 1e6 + gaps_s();
  }
  Command stm(size_t i) const {
    return StepperMove{motor, dir, microstep, static_cast<uint32_t>(pieces[i].steps), pieces[i].delay_us};
  }
  // With our firmware every move sets the acceleration first (0: the board must not ramp).
  Command set_accel() const { return SetSetting{motor, proto::kSettingAccel, firmware_ramp ? accel : 0}; }
};

std::optional<Problem> to_pieces(const std::vector<Slice>& slices, const std::string& name,
                                 std::vector<Piece>& out) {
  for (const Slice& s : slices) {
    const double delay = 1e6 / s.rate;
    if (!(delay <= kMaxDelayUs + 0.5)) {
      return Problem{"a rate of at least one step per 89 s", num(s.rate) + " steps/s",
                     name + " would step at " + num(s.rate) +
                         " steps/s, slower than the board can time (one step per 89 s)"};
    }
    out.push_back({s.steps, static_cast<uint32_t>(std::max(1.0, std::round(delay)))});
  }
  return std::nullopt;
}

std::optional<Problem> check_rates(const MotorPlan& plan, const std::string& name) {
  for (const Piece& p : plan.pieces) {
    if (board_rate(p.delay_us) > kMaxRate || p.delay_us < kMinDelayUs) {
      const std::string rate = num(1e6 / p.delay_us) + " steps/s";
      return Problem{"at most " + std::to_string(kMaxRate) + " steps/s", rate,
                     name + " would step at " + rate + ", faster than the board's " +
                         std::to_string(kMaxRate) + " steps/s"};
    }
    if (p.delay_us > kMaxDelayUs) {
      return Problem{"a rate of at least one step per 89 s", num(1e6 / p.delay_us) + " steps/s",
                     name + " would step slower than the board can time (one step per 89 s)"};
    }
  }
  return std::nullopt;
}

// Plans one motor's move of `steps` (> 0) in `dir`. With `fit`, the move is slowed by `r`
// (speed / r, accel / r², jerk / r³: the same shape taking r times as long) and made to take
// fit->target_s; a plan that cannot is a Problem (the caller tries another shape).
// Fits the pieces after `first` to make the move take `target_s`, the pauses between pieces
// included. Splitting a piece in two adds a pause, which the split must then make up for, so
// both ways are tried — the pieces as they are (one delay for the longest), and split with the
// pause counted — and the closer one kept.
void fit_with_gaps(MotorPlan& plan, size_t first, double fixed_us, double target_s, bool keep_first,
                   double tolerance_s) {
  const std::vector<Piece> head(plan.pieces.begin(), plan.pieces.begin() + static_cast<std::ptrdiff_t>(first));
  const std::vector<Piece> original(plan.pieces.begin() + static_cast<std::ptrdiff_t>(first), plan.pieces.end());
  const auto with = [&](const std::vector<Piece>& tail) {
    MotorPlan p = plan;
    p.pieces = head;
    p.pieces.insert(p.pieces.end(), tail.begin(), tail.end());
    return p;
  };
  const auto fitted = [&](double gaps_s) {
    std::vector<Piece> tail = original;
    fit_duration(tail, (target_s - gaps_s) * 1e6 - fixed_us, keep_first);
    return with(tail);
  };
  // As they are: the longest piece at the one delay closest to filling the time.
  std::vector<MotorPlan> candidates;
  {
    std::vector<Piece> tail = original;
    const size_t from = keep_first && tail.size() > 1 ? 1 : 0;
    if (tail.size() > from) {
      size_t m = from;
      for (size_t i = from + 1; i < tail.size(); ++i) {
        if (tail[i].steps > tail[m].steps) m = i;
      }
      double others = fixed_us + with(original).gaps_s() * 1e6;
      for (size_t i = 0; i < tail.size(); ++i) {
        if (i != m) others += static_cast<double>(tail[i].steps) * tail[i].delay_us;
      }
      const double mean = (target_s * 1e6 - others) / static_cast<double>(tail[m].steps);
      if (mean >= kMinDelayUs && mean < kMaxDelayUs) {
        tail[m].delay_us = static_cast<uint32_t>(std::llround(mean));
        candidates.push_back(with(tail));
      }
    }
  }
  candidates.push_back(fitted(with(original).gaps_s()));
  // Split: the pause a split adds, measured on a trial split, then settled in a few rounds.
  double gaps = candidates.back().pieces.size() > plan.pieces.size() ? candidates.back().gaps_s() : -1.0;
  if (gaps < 0) {
    std::vector<Piece> trial = original;
    size_t m = 0;
    for (size_t i = 1; i < trial.size(); ++i) {
      if (trial[i].steps > trial[m].steps) m = i;
    }
    if (!trial.empty() && trial[m].steps > 1) {
      const Piece whole = trial[m];
      trial[m].steps = whole.steps - 1;
      trial.insert(trial.begin() + static_cast<std::ptrdiff_t>(m) + 1, Piece{1, whole.delay_us + 1});
      gaps = with(trial).gaps_s();
    }
  }
  for (int round = 0; round < 3 && gaps >= 0; ++round) {
    MotorPlan p = fitted(gaps);
    const double now = p.gaps_s();
    candidates.push_back(std::move(p));
    if (std::fabs(now - gaps) < 1e-9) break;
    gaps = now;
  }
  const auto error = [&](const MotorPlan& p) { return std::fabs(p.duration_s() - target_s); };
  // Fewer pieces, fewer pauses whose length the board's timing makes uncertain.
  if (error(candidates[0]) <= tolerance_s) {
    plan = candidates[0];
    return;
  }
  plan = *std::min_element(candidates.begin(), candidates.end(),
                           [&](const MotorPlan& x, const MotorPlan& y) { return error(x) < error(y); });
}

Result<MotorPlan, Problem> plan_motor(const Move& move, const MotorConfig& config, uint64_t steps,
                                      uint32_t dir, const LinkTiming& link, double r, const Fit* fit) {
  const TargetFirmware firmware = link.firmware;
  const Profile& pr = move.profile;
  const std::string& name = config.name;
  MotorPlan plan;
  plan.link = link;
  plan.motor = config.motor;
  plan.microstep = config.microstep;
  plan.dir = dir;
  plan.steps = steps;
  if (!(pr.speed > 0)) {
    return Problem{"a speed above 0 steps/s", num(pr.speed), name + "'s move needs a speed above 0"};
  }
  const bool ramped = pr.kind == ProfileKind::kTrapezoid || pr.kind == ProfileKind::kSCurve;
  if (ramped && !(pr.accel > 0)) {
    return Problem{"an acceleration above 0 steps/s²", num(pr.accel),
                   name + "'s ramped move needs an acceleration above 0"};
  }
  if (pr.kind == ProfileKind::kSCurve && !(pr.jerk > 0)) {
    return Problem{"a jerk above 0 steps/s³", num(pr.jerk), name + "'s S-curve needs a jerk above 0"};
  }
  const Shape shape = fit ? fit->shape : Shape::kAsked;
  const double speed = pr.speed / r, accel = pr.accel / (r * r), jerk = pr.jerk / (r * r * r);
  const auto distance = static_cast<double>(steps);
  std::vector<Slice> slices;
  if (shape == Shape::kConstant) {
    slices.assign(1, Slice{steps, fit ? distance / fit->target_s : speed});
  } else {
    switch (pr.kind) {
      case ProfileKind::kConstant: slices.assign(1, Slice{steps, speed}); break;
      case ProfileKind::kStaged: slices = staged(steps, speed, accel, pr.stages); break;
      case ProfileKind::kTrapezoid:
        if (firmware == TargetFirmware::kV2 && shape == Shape::kAsked) {
          if (fit) {
            plan.firmware_ramp = true;
            auto lines_ok = [&](uint32_t d, uint32_t acc) {
              plan.pieces = {{steps, d}};
              plan.accel = acc;
              return (fit->stm_chars == 0 || chars(plan.stm(0)) == fit->stm_chars) &&
                     (fit->set_chars == 0 || chars(plan.set_accel()) == fit->set_chars);
            };
            const std::optional<FirmwareRamp> fr =
                fit_ramp(steps, speed, accel, std::round(pr.accel), fit->target_s, lines_ok);
            if (!fr) return Problem{};
            plan.pieces = {{steps, fr->delay_us}};
            plan.accel = fr->accel;
            if (auto p = check_rates(plan, name)) return *p;
            break;
          }
          // A move too short to reach its speed is sent with its peak as the rate: the same
          // motion, and the board checks its budget and longest ramp against the rate sent.
          const double acc = std::round(accel);
          double delay = std::max(1.0, std::round(1e6 / speed));
          if (acc >= 1 && 1e6 / delay > std::sqrt(acc * distance)) {
            delay = std::max(delay, std::floor(1e6 / std::sqrt(acc * distance)));
          }
          if (acc >= 1 && acc <= kMaxAccel && delay <= kMaxDelayUs && 1e6 / delay / acc <= kMaxRampS) {
            plan.firmware_ramp = true;
            plan.pieces = {{steps, static_cast<uint32_t>(delay)}};
            plan.accel = static_cast<uint32_t>(acc);
            if (auto p = check_rates(plan, name)) return *p;
            break;
          }
          // The board cannot ramp this (too gentle, or too hard): the same trapezoid as stages.
        }
        slices = sampled(trapezoid(distance, speed, accel), steps, kTrapezoidSlices);
        break;
      case ProfileKind::kSCurve: slices = sampled(s_curve(distance, speed, accel, jerk), steps, kSCurveSlices); break;
    }
  }
  if (!plan.firmware_ramp) {
    if (auto p = to_pieces(slices, name, plan.pieces)) return *p;
    if (fit) fit_with_gaps(plan, 0, 0.0, fit->target_s, fit->keep_first, fit->tolerance_s);
    if (auto p = check_rates(plan, name)) return *p;
  }
  if (fit) {
    if (std::fabs(plan.duration_s() - fit->target_s) > fit->tolerance_s) return Problem{};
    if (fit->stm_chars != 0 && chars(plan.stm(0)) != fit->stm_chars) return Problem{};
    if (fit->set_chars != 0 && chars(plan.set_accel()) != fit->set_chars) return Problem{};
  }
  return plan;
}

std::string profile_words(const Profile& p) {
  switch (p.kind) {
    case ProfileKind::kConstant: return "constant, " + num(p.speed) + " steps/s";
    case ProfileKind::kStaged:
      return "staged, " + std::to_string(p.stages) + " rates up to " + num(p.speed) + " steps/s" +
             (p.accel > 0 ? ", " + num(p.accel) + " steps/s²" : "");
    case ProfileKind::kTrapezoid: return "trapezoid, " + num(p.speed) + " steps/s, " + num(p.accel) + " steps/s²";
    case ProfileKind::kSCurve:
      return "S-curve, " + num(p.speed) + " steps/s, " + num(p.accel) + " steps/s², " + num(p.jerk) + " steps/s³";
  }
  return "";
}

std::string colour_words(const Colour& c) {
  return std::to_string(c.r) + "," + std::to_string(c.g) + "," + std::to_string(c.b) + "," + std::to_string(c.w);
}

bool has_location(const Location& l) { return l.line != 0 || !l.path.empty(); }


// ---------------------------------------------------------------------------------------
// The planner: walks the file once, keeping time, positions and what is still moving

class Planner {
 public:
  Planner(const MotionFile& file, const PlanOptions& options) : file_(file), options_(options) {
    for (uint32_t m = 0; m < proto::kMotorCount; ++m) {
      motors_[m].position = options.start_position[m].value_or(0);
      motors_[m].known = options.start_position[m].has_value();
    }
  }

  Result<Plan, std::vector<FileError>> run() {
    walk(file_.steps, "");
    check_budget();
    if (!errors_.empty()) {
      std::stable_sort(errors_.begin(), errors_.end(), [](const FileError& a, const FileError& b) {
        return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
      });
      return errors_;
    }
    plan_.duration_s = now_;
    for (const MotorState& ms : motors_) plan_.duration_s = std::max(plan_.duration_s, ms.busy_until);
    for (const MotorConfig& c : file_.motors) plan_.tracks.push_back(track(c));
    return std::move(plan_);
  }

 private:
  struct MotorState {
    int64_t position = 0;  // steps; when not known, counted from wherever the motor was
    bool known = false;
    double busy_until = 0;
    // The last motion, while a stop may still cut it short.
    bool moving = false;
    size_t action = 0, slot = 0, first_point = 0, first_boundary = 0;
    double brake = 0;  // the acceleration it brakes at when stopped (0: stops at once)
    std::vector<VelocityPoint> velocity;
    std::vector<double> boundaries;
  };

  void error(const Location& where, std::string expected, std::string found, std::string message) {
    errors_.push_back(FileError{where, std::move(expected), std::move(found), std::move(message)});
  }

  const MotorConfig* motor(const std::string& name, const Location& where) {
    for (const MotorConfig& c : file_.motors) {
      if (c.name == name) {
        if (c.motor >= 1 && c.motor <= proto::kMotorCount) return &c;
        break;
      }
    }
    error(where, "a motor named in \"motors\"", name, "there is no motor named " + name);
    return nullptr;
  }

  double all_rest() const {
    double t = now_;
    for (const MotorState& ms : motors_) t = std::max(t, ms.busy_until);
    return t;
  }

  // Every command the plan sends must be one the board accepts.
  void check(const Command& command, const Location& where) {
    const Result<Command, Diagnostic> v = validate(command);
    if (!v.ok()) error(where, "a command the board accepts", describe(command), v.error().message);
  }

  Action& begin(ActionKind kind, const Step& step, const std::string& words, const std::string& pass, double start) {
    Action a;
    a.kind = kind;
    a.index = plan_.actions.size() + 1;
    a.description = step.label.empty() ? words + pass : step.label;
    a.where = step.where;
    a.start_s = a.end_s = start;
    plan_.actions.push_back(std::move(a));
    return plan_.actions.back();
  }

  void walk(const std::vector<Step>& steps, const std::string& pass) {
    for (const Step& step : steps) {
      if (const auto* r = std::get_if<RepeatStep>(&step.action)) {
        for (uint32_t i = 1; i <= r->count; ++i) {
          const std::string mine = "repeat " + std::to_string(i) + " of " + std::to_string(r->count);
          walk(r->steps, pass.empty() ? " (" + mine + ")" : pass.substr(0, pass.size() - 1) + ", " + mine + ")");
        }
      } else if (const auto* h = std::get_if<HomeStep>(&step.action)) {
        home(step, *h, pass);
      } else if (const auto* m = std::get_if<MoveStep>(&step.action)) {
        moves(step, {&m->move}, false, m->wait, pass);
      } else if (const auto* t = std::get_if<TogetherStep>(&step.action)) {
        std::vector<const Move*> list;
        for (const Move& mv : t->moves) list.push_back(&mv);
        moves(step, list, true, true, pass);
      } else if (const auto* s = std::get_if<ServoStep>(&step.action)) {
        servo(step, *s, pass);
      } else if (const auto* l = std::get_if<LedStep>(&step.action)) {
        led(step, *l, pass);
      } else if (const auto* w = std::get_if<WaitStep>(&step.action)) {
        wait(step, *w, pass);
      } else if (const auto* st = std::get_if<StopStep>(&step.action)) {
        stop(step, *st, pass);
      }
    }
  }

  // Homing: every motor must rest first (seed rule [2]); one motor after another.
  void home(const Step& step, const HomeStep& h, const std::string& pass) {
    std::string words = "home";
    std::vector<const MotorConfig*> configs;
    for (const std::string& name : h.motors) {
      words += (words == "home" ? " " : ", ") + name;
      const MotorConfig* c = motor(name, step.where);
      if (c == nullptr) continue;
      if (!proto::motor_has_switches(c->motor)) {
        error(step.where, "a motor with limit switches (1 or 2)", name + " (motor " + std::to_string(c->motor) + ")",
              name + " is motor " + std::to_string(c->motor) + ", which has no limit switch to home against");
        continue;
      }
      configs.push_back(c);
    }
    Action& a = begin(ActionKind::kHome, step, words, pass, all_rest());
    a.estimated = true;
    for (const MotorConfig* c : configs) {
      const Command cmd = StepperMove{c->motor, proto::kActionHome, c->microstep, 0, 0};
      check(cmd, step.where);
      a.commands_at_s.push_back(a.end_s);
      a.commands.push_back(cmd);
      a.motors.push_back(c->motor);
      a.end_s += kHomeEstimateS;
    }
    for (const MotorConfig* c : configs) {
      MotorState& ms = motors_[c->motor - 1];
      ms.position = 0;
      ms.known = true;
      ms.busy_until = a.end_s;
      ms.moving = false;
    }
    now_ = a.end_s;
  }

  struct Item {
    const Move* move = nullptr;
    const MotorConfig* config = nullptr;
    Location where;
    int64_t delta = 0;
    MotorPlan natural, plan;
    bool planned = false;
  };

  // Lines sent for a move: setup first, then the first STM of each motor. Start offsets per item.
  std::vector<double> offsets(const std::vector<Item>& items, std::vector<Command>& setup) const {
    setup.clear();
    if (options_.firmware == TargetFirmware::kV2) {
      for (const Item& it : items) {
        if (!it.planned) continue;
        setup.push_back(it.plan.set_accel());
      }
    }
    // The runner sends a line once the one before is answered (our firmware): each line costs
    // its wire time, the board's main-loop pass and its reply's wire time; a motor starts when
    // its own line has arrived and been read.
    const bool answered = options_.firmware == TargetFirmware::kV2;
    const double reply = answered ? wire_s(encode_board_frame(BoardFrame{Ack{}}).value().size() + 1, options_.baud) : 0.0;
    const double read = answered ? kBoardLoopS : 0.0;
    double t = 0;
    for (const Command& c : setup) t += wire_s(c, options_.baud) + read + reply;
    std::vector<double> out;
    for (const Item& it : items) {
      if (it.planned) {
        t += wire_s(it.plan.stm(0), options_.baud) + read;
        out.push_back(t);
        t += reply;
      } else {
        out.push_back(t);
      }
    }
    return out;
  }

  // Makes one motor's move take `target_s` (>= its own duration): its profile slowed, else the
  // same ramp as stages, else one rate. Lengths (when not 0) are lines that must not change.
  bool fit_item(Item& it, double target_s, size_t stm_chars, size_t set_chars) const {
    const double own = it.natural.duration_s();
    auto lines_ok = [&](const MotorPlan& p) {
      return (stm_chars == 0 || chars(p.stm(0)) == stm_chars) && (set_chars == 0 || chars(p.set_accel()) == set_chars);
    };
    if (target_s <= own + 1e-9 && lines_ok(it.natural)) {
      it.plan = it.natural;
      return true;
    }
    for (Shape shape : {Shape::kAsked, Shape::kStaircase, Shape::kConstant}) {
      for (bool keep_first : {false, true}) {
        const Fit fit{target_s, shape, keep_first, stm_chars, set_chars, tolerance_s_};
        Result<MotorPlan, Problem> p = plan_motor(*it.move, *it.config, it.natural.steps, it.natural.dir,
                                                  it.natural.link, std::max(1.0, target_s / own), &fit);
        if (p.ok()) {
          it.plan = p.value();
          return true;
        }
      }
    }
    return false;
  }

  // Coordinated: every motor ends when the last would (E = the latest start + own duration);
  // the others are slowed to end then too. A motor starts when its STM line has arrived, after
  // the setup lines and the STM lines before it, so each fit moves the starts of the motors
  // after it by the change in its line's length: a few rounds settle that, and a last round, if
  // needed, fits each motor keeping its lines' lengths so that no start moves any more.
  void coordinate(std::vector<Item>& items) {
    size_t moving = 0;
    for (const Item& it : items) moving += it.planned ? 1 : 0;
    if (moving < 2) return;
    double shortest_s = 1e9, longest_s = 0;
    for (const Item& it : items) {
      if (!it.planned) continue;
      for (const Piece& p : it.natural.pieces) {
        shortest_s = std::min(shortest_s, p.delay_us / 1e6);
        longest_s = std::max(longest_s, p.delay_us / 1e6);
      }
    }
    // The seed's stages follow one another by the host's clock, with a margin that grows with
    // each stage (session.h): splitting a run to end closer only moves the end by that margin,
    // so with the seed the motors end within one step period of the slowest of them.
    tolerance_s_ = std::max(kSyncToleranceS, options_.firmware == TargetFirmware::kSeed ? longest_s : shortest_s) / 2;
    std::vector<Command> setup;
    std::vector<double> off = offsets(items, setup);
    auto latest = [&] {
      double end = 0;
      for (size_t k = 0; k < items.size(); ++k) {
        if (items[k].planned) end = std::max(end, off[k] + items[k].natural.duration_s());
      }
      return end;
    };
    bool settled = false;
    for (int round = 0; round < 4 && !settled; ++round) {
      const double end = latest();
      for (size_t k = 0; k < items.size(); ++k) {
        Item& it = items[k];
        if (!it.planned || fit_item(it, end - off[k], 0, 0)) continue;
        const double need = end - off[k];
        const bool too_few = need > static_cast<double>(it.natural.steps) * kMaxDelayUs / 1e6;
        error(it.where, "a move that can be slowed to " + num(need) + " s", profile_words(it.move->profile),
              it.config->name + " cannot be slowed to arrive with the other motors: it would have to take " +
                  num(need) + " s" +
                  (too_few ? ", and " + std::to_string(it.natural.steps) + " steps take at most 89 s each" : ""));
        it.planned = false;
      }
      std::vector<double> again = offsets(items, setup);
      settled = again == off;
      off = std::move(again);
    }
    if (settled) return;
    double end = 0;
    for (size_t k = 0; k < items.size(); ++k) {
      if (items[k].planned) end = std::max(end, off[k] + items[k].plan.duration_s());
    }
    for (size_t k = 0; k < items.size(); ++k) {
      Item& it = items[k];
      if (it.planned && std::fabs(off[k] + it.plan.duration_s() - end) > tolerance_s_) refit_tail(it, end - off[k]);
    }
  }

  // The last round of coordinating: the move's lines keep their length (the first STM stays as
  // it is, or our firmware's trapezoid keeps its lines' lengths), so no motor's start moves.
  bool refit_tail(Item& it, double target_s) const {
    MotorPlan p = it.plan;
    const bool v2 = options_.firmware == TargetFirmware::kV2;
    if (p.firmware_ramp) return fit_item(it, target_s, chars(p.stm(0)), v2 ? chars(p.set_accel()) : 0);
    std::vector<Piece> tail(p.pieces.begin() + 1, p.pieces.end());
    p.pieces.resize(1);
    if (tail.empty()) {  // one run: split off a head whose line is as long as the whole run's
      const size_t want = chars(p.stm(0));
      const uint64_t n = p.pieces[0].steps;
      for (uint64_t h = n - 1; h >= 1 && n - h <= 2000 && tail.empty(); --h) {
        p.pieces[0].steps = h;
        if (chars(p.stm(0)) == want) tail.push_back({n - h, p.pieces[0].delay_us});
      }
      if (tail.empty()) return false;
    }
    p.pieces.insert(p.pieces.end(), tail.begin(), tail.end());
    fit_with_gaps(p, 1, static_cast<double>(p.pieces[0].steps) * p.pieces[0].delay_us, target_s, false, tolerance_s_);
    if (check_rates(p, it.config->name) || std::fabs(p.duration_s() - target_s) > tolerance_s_) return false;
    it.plan = p;
    return true;
  }

  void moves(const Step& step, const std::vector<const Move*>& list, bool together, bool wait,
             const std::string& pass) {
    std::vector<Item> items;
    std::string words = together ? "together:" : "move";
    for (const Move* mv : list) {
      Item it;
      it.move = mv;
      it.where = has_location(mv->where) ? mv->where : step.where;
      it.config = motor(mv->motor, it.where);
      if (it.config == nullptr) continue;
      for (const Item& other : items) {
        if (other.config->motor == it.config->motor) {
          error(it.where, "each motor once in a coordinated move", mv->motor, mv->motor + " is moved twice at once");
        }
      }
      MotorState& ms = motors_[it.config->motor - 1];
      const int64_t target = std::llround(mv->distance);
      std::string what;
      if (mv->absolute) {
        if (!ms.known) {
          error(it.where, "a known position (home first, or a relative move)", "an unknown position",
                "the position of " + mv->motor + " is not known here: home it first, or move it by a relative distance");
          continue;
        }
        it.delta = target - ms.position;
        what = " to " + std::to_string(target) + " (" + signed_steps(it.delta) + ")";
      } else {
        it.delta = target;
        what = " " + signed_steps(it.delta);
      }
      words += (items.empty() ? " " : ", ") + mv->motor + what + " (" + profile_words(mv->profile) + ")";
      if (static_cast<uint64_t>(std::llabs(it.delta)) > proto::kIntMax) {
        error(it.where, "at most " + std::to_string(proto::kIntMax) + " steps", std::to_string(it.delta),
              mv->motor + "'s move is longer than one STM can count");
        continue;
      }
      if (ms.known) {
        const int64_t end = ms.position + it.delta;
        const MotorConfig& c = *it.config;
        const auto e = static_cast<double>(end);
        if ((c.min_position && e < *c.min_position) || (c.max_position && e > *c.max_position)) {
          const bool low = c.min_position && e < *c.min_position;
          const double limit = low ? *c.min_position : *c.max_position;
          error(it.where, std::string(low ? "a position of at least " : "a position of at most ") + num(limit),
                std::to_string(end),
                mv->motor + " would end at " + std::to_string(end) + " steps, beyond its soft limit of " +
                    num(limit) + " steps");
        }
      }
      items.push_back(std::move(it));
    }
    if (!wait) words += ", without waiting";
    if (together) words += ", arriving together";

    double start = now_;
    for (const Item& it : items) start = std::max(start, motors_[it.config->motor - 1].busy_until);
    Action& a = begin(ActionKind::kMove, step, words, pass, start);
    a.wait_for_motors = wait;
    const size_t action_index = plan_.actions.size() - 1;

    for (Item& it : items) {
      a.motors.push_back(it.config->motor);
      if (it.delta == 0) continue;  // nothing to do: an STM of 0 steps would run until stopped
      const uint32_t dir = it.delta > 0 ? proto::kActionForward : proto::kActionReverse;
      const int64_t start_units = motors_[it.config->motor - 1].position * 256 / it.config->microstep;
      const LinkTiming link{options_.baud, options_.firmware, start_units};
      Result<MotorPlan, Problem> p = plan_motor(*it.move, *it.config, static_cast<uint64_t>(std::llabs(it.delta)),
                                                dir, link, 1.0, nullptr);
      if (!p.ok()) {
        error(it.where, p.error().expected, p.error().found, p.error().message);
        continue;
      }
      it.natural = it.plan = p.value();
      it.planned = true;
    }

    if (together) coordinate(items);
    std::vector<Command> setup;
    const std::vector<double> off = offsets(items, setup);

    a.setup = setup;
    for (const Command& c : setup) check(c, step.where);
    double last_end = start;
    for (size_t k = 0; k < items.size(); ++k) {
      Item& it = items[k];
      MotorState& ms = motors_[it.config->motor - 1];
      ms.position += it.delta;
      std::vector<Stage> stages;
      if (it.planned) {
        const double t0 = start + off[k];
        ms.first_point = ms.velocity.size();
        ms.first_boundary = ms.boundaries.size();
        const double sign = it.plan.dir == proto::kActionForward ? 1.0 : -1.0;
        double t = t0;
        ms.velocity.push_back({t0, 0});
        for (size_t i = 0; i < it.plan.pieces.size(); ++i) {
          const Piece& pc = it.plan.pieces[i];
          if (i > 0) t += it.plan.gap_s(i);  // the runner sends a stage once the one before has ended
          Stage s{it.plan.motor, it.plan.dir, it.plan.microstep, static_cast<uint32_t>(pc.steps), pc.delay_us, t, 0};
          check(it.plan.stm(i), it.where);
          if (it.plan.firmware_ramp) {
            const Ideal p = trapezoid(static_cast<double>(pc.steps), 1e6 / pc.delay_us, it.plan.accel);
            for (const Segment& sg : p.segments()) ms.velocity.push_back({t0 + sg.t0 + sg.dur, sign * sg.v(sg.dur)});
            s.end_s = t0 + it.plan.duration_s();
            ms.velocity.back() = {s.end_s, 0};
          } else {
            s.end_s = t + static_cast<double>(pc.steps) * pc.delay_us / 1e6;
            if (it.plan.pieces.size() > 1) ms.boundaries.push_back(t);
            ms.velocity.push_back({t, sign * 1e6 / pc.delay_us});
            ms.velocity.push_back({s.end_s, sign * 1e6 / pc.delay_us});
          }
          t = s.end_s;
          stages.push_back(s);
        }
        if (!it.plan.firmware_ramp) ms.velocity.push_back({t, 0});
        ms.busy_until = t;
        ms.moving = true;
        ms.action = action_index;
        ms.slot = a.stages.size();
        ms.brake = it.plan.firmware_ramp ? it.plan.accel : 0;
        last_end = std::max(last_end, t);
      }
      a.stages.push_back(std::move(stages));
    }
    a.end_s = wait ? last_end : start;
    now_ = a.end_s;
  }

  // The seed's firmware refuses servo and LED frames while a stepper runs (seed rule [5]).
  double accessory_start() const { return options_.firmware == TargetFirmware::kSeed ? all_rest() : now_; }

  void servo(const Step& step, const ServoStep& s, const std::string& pass) {
    Action& a = begin(ActionKind::kServo, step, "servo " + std::to_string(s.servo) + " to " + num(s.angle) + "°", pass,
                      accessory_start());
    a.wait_for_motors = false;
    const Command cmd = ServoMove{s.servo, static_cast<uint32_t>(std::max(0.0, std::round(s.angle)))};
    check(cmd, step.where);
    a.commands.push_back(cmd);
    a.commands_at_s.push_back(a.start_s);
    now_ = a.end_s;
  }

  // A fade: one LED frame every 50 ms at most, the first the starting colour, the last the target.
  void led(const Step& step, const LedStep& l, const std::string& pass) {
    const size_t strip = std::clamp<uint32_t>(l.strip, 1, proto::kStripCount) - 1;
    const Colour from = l.from ? *l.from : strips_[strip];
    const bool fade = l.fade_ms > 0;
    std::string words = "LED strip " + std::to_string(l.strip);
    words += fade ? " fade from " + colour_words(from) + " to " + colour_words(l.colour) + " in " + num(l.fade_ms) + " ms"
                  : " to " + colour_words(l.colour);
    Action& a = begin(ActionKind::kLed, step, words, pass, accessory_start());
    a.wait_for_motors = false;
    const double fade_s = l.fade_ms / 1000.0;
    const size_t frames = fade ? std::max<size_t>(2, static_cast<size_t>(std::ceil(fade_s / kFadeFrameS - 1e-9)) + 1) : 1;
    for (size_t i = 0; i < frames; ++i) {
      const double f = frames == 1 ? 1.0 : static_cast<double>(i) / static_cast<double>(frames - 1);
      auto mix = [f](uint32_t x, uint32_t y) {
        return static_cast<uint32_t>(std::lround(x + (static_cast<double>(y) - x) * f));
      };
      const Command cmd = LedColor{l.strip, mix(from.r, l.colour.r), mix(from.g, l.colour.g), mix(from.b, l.colour.b),
                                   mix(from.w, l.colour.w)};
      check(cmd, step.where);
      a.commands.push_back(cmd);
      a.commands_at_s.push_back(a.start_s + fade_s * f);
    }
    a.end_s = a.start_s + (fade ? fade_s : 0);
    strips_[strip] = l.colour;
    now_ = a.end_s;
  }

  void wait(const Step& step, const WaitStep& w, const std::string& pass) {
    if (!w.until_done.empty()) {
      std::string words = "wait until";
      std::vector<uint32_t> numbers;
      double end = now_;
      for (const std::string& name : w.until_done) {
        words += (numbers.empty() ? " " : ", ") + name;
        if (const MotorConfig* c = motor(name, step.where)) {
          numbers.push_back(c->motor);
          end = std::max(end, motors_[c->motor - 1].busy_until);
        }
      }
      Action& a = begin(ActionKind::kWait, step, words + (numbers.size() > 1 ? " rest" : " rests"), pass, now_);
      a.motors = numbers;
      a.end_s = end;
    } else {
      Action& a = begin(ActionKind::kWait, step, "wait " + num(w.ms) + " ms", pass, now_);
      a.wait_for_motors = false;
      a.end_s = a.start_s + std::max(0.0, w.ms) / 1000.0;
    }
    now_ = plan_.actions.back().end_s;
  }

  // A stop cuts the motion of a motor still running: at once, or braking at its acceleration.
  void stop(const Step& step, const StopStep& s, const std::string& pass) {
    std::vector<uint32_t> numbers;
    std::string words = "stop";
    if (s.motors.empty()) {
      words += " all motors";
      for (uint32_t m = 1; m <= proto::kMotorCount; ++m) numbers.push_back(m);
    }
    for (const std::string& name : s.motors) {
      words += (numbers.empty() ? " " : ", ") + name;
      if (const MotorConfig* c = motor(name, step.where)) numbers.push_back(c->motor);
    }
    Action& a = begin(ActionKind::kStop, step, words, pass, now_);
    const size_t index = plan_.actions.size() - 1;
    double end = a.start_s;
    for (uint32_t m : numbers) {
      const Command cmd = StepperMove{m, proto::kActionStop, 0, 0, 0};
      check(cmd, step.where);
      plan_.actions[index].commands.push_back(cmd);
      plan_.actions[index].commands_at_s.push_back(plan_.actions[index].start_s);
      plan_.actions[index].motors.push_back(m);
      end = std::max(end, cut(m, plan_.actions[index].start_s));
    }
    plan_.actions[index].end_s = end;
    now_ = end;
  }

  // Cuts motor m's running motion at t; returns when it rests.
  double cut(uint32_t m, double t) {
    MotorState& ms = motors_[m - 1];
    if (!ms.moving || ms.busy_until <= t) return t;
    std::vector<VelocityPoint>& pts = ms.velocity;
    double v = 0;
    for (size_t i = ms.first_point; i + 1 < pts.size(); ++i) {
      if (pts[i].t_s <= t && t < pts[i + 1].t_s) {
        const double f = (t - pts[i].t_s) / (pts[i + 1].t_s - pts[i].t_s);
        v = pts[i].velocity + (pts[i + 1].velocity - pts[i].velocity) * f;
      }
    }
    size_t keep = ms.first_point;
    while (keep < pts.size() && pts[keep].t_s < t) ++keep;
    pts.resize(keep);
    pts.push_back({t, v});
    const double rest = ms.brake > 0 ? t + std::fabs(v) / ms.brake : t;
    pts.push_back({rest, 0});
    size_t kb = ms.first_boundary;
    while (kb < ms.boundaries.size() && ms.boundaries[kb] < t) ++kb;
    ms.boundaries.resize(kb);
    std::vector<Stage>& stages = plan_.actions[ms.action].stages[ms.slot];
    while (!stages.empty() && stages.back().start_s >= t) stages.pop_back();
    if (!stages.empty()) stages.back().end_s = rest;
    ms.busy_until = rest;
    ms.known = false;
    ms.moving = false;
    return rest;
  }

  // The board refuses a move whose rate takes the sum over moving motors beyond its budget:
  // checked when each stage starts, against the stage each other motor is running then.
  void check_budget() {
    struct Run {
      double start, end;
      uint32_t rate;
      bool ramping;
      size_t action;
    };
    std::array<std::vector<Run>, proto::kMotorCount> runs;  // per motor, in time order
    for (size_t i = 0; i < plan_.actions.size(); ++i) {
      const Action& a = plan_.actions[i];
      for (const std::vector<Stage>& stages : a.stages) {
        for (const Stage& s : stages) {
          bool ramping = false;
          for (const Command& c : a.setup) {
            const auto* set = std::get_if<SetSetting>(&c);
            if (set && set->motor == s.motor && set->setting == proto::kSettingAccel && set->value > 0) ramping = true;
          }
          runs[s.motor - 1].push_back({s.start_s, s.end_s, board_rate(std::max(1u, s.delay_us)), ramping, i});
        }
      }
    }
    std::vector<size_t> reported;
    for (uint32_t m = 0; m < proto::kMotorCount; ++m) {
      for (const Run& r : runs[m]) {
        uint32_t sum = r.rate;
        bool ramping = r.ramping;
        for (uint32_t o = 0; o < proto::kMotorCount; ++o) {
          if (o == m) continue;
          // The other motor's last stage starting by then, if it still runs.
          auto after = std::upper_bound(runs[o].begin(), runs[o].end(), r.start + 1e-12,
                                        [](double t, const Run& x) { return t < x.start; });
          if (after == runs[o].begin() || std::prev(after)->end <= r.start + 1e-9) continue;
          sum += std::prev(after)->rate;
          ramping = ramping || std::prev(after)->ramping;
        }
        const uint32_t limit = ramping ? kRampingBudget : kBudget;
        if (sum <= limit || std::find(reported.begin(), reported.end(), r.action) != reported.end()) continue;
        reported.push_back(r.action);
        error(plan_.actions[r.action].where, "at most " + std::to_string(limit) + " steps/s in all",
              std::to_string(sum) + " steps/s",
              "the motors moving at once would step " + std::to_string(sum) + " times a second in all; the board allows " +
                  std::to_string(limit) + (ramping ? " while any of them ramps" : ""));
      }
    }
  }

  MotorTrack track(const MotorConfig& c) const {
    const MotorState& ms = motors_[c.motor - 1];
    MotorTrack t;
    t.name = c.name;
    t.motor = c.motor;
    t.microstep = c.microstep;
    const std::optional<int64_t>& start = options_.start_position[c.motor - 1];
    t.start_known = start.has_value();
    t.start_position = start.value_or(0);
    t.end_known = ms.known;
    t.end_position = ms.position;
    auto add = [&t](VelocityPoint p) {
      if (!t.velocity.empty() && t.velocity.back().t_s == p.t_s && t.velocity.back().velocity == p.velocity) return;
      t.velocity.push_back(p);
    };
    if (ms.velocity.empty() || ms.velocity.front().t_s > 0) add({0, 0});
    for (const VelocityPoint& p : ms.velocity) add(p);
    if (t.velocity.back().t_s < plan_.duration_s) add({plan_.duration_s, 0});
    t.stage_boundaries_s = ms.boundaries;
    return t;
  }

  const MotionFile& file_;
  const PlanOptions& options_;
  std::array<MotorState, proto::kMotorCount> motors_;
  std::array<Colour, proto::kStripCount> strips_{};  // black at the start of the file
  double now_ = 0;
  std::vector<FileError> errors_;
  double tolerance_s_ = kSyncToleranceS / 2;  // this coordinated move's (coordinate())
  Plan plan_;
};

}  // namespace

Result<Plan, std::vector<FileError>> plan_motion(const MotionFile& file, const PlanOptions& options) {
  return Planner(file, options).run();
}

}  // namespace hmc::motion
