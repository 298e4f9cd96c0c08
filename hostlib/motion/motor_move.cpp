// One motor's move planned alone (motor_move.h).
#include "motor_move.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/session.h"

namespace hmc::motion::planning {
namespace {

constexpr int kTrapezoidSlices = 8;
constexpr int kSCurveSlices = 12;

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

std::optional<Problem> to_pieces(const std::vector<Slice>& slices, const std::string& name, std::vector<Piece>& out) {
  for (const Slice& s : slices) {
    const double delay = 1e6 / s.rate;
    if (!(delay <= kMaxDelayUs + 0.5)) {
      return Problem{
          "a rate of at least one step per 89 s", num(s.rate) + " steps/s",
          name + " would step at " + num(s.rate) + " steps/s, slower than the board can time (one step per 89 s)"};
    }
    out.push_back({s.steps, static_cast<uint32_t>(std::max(1.0, std::round(delay)))});
  }
  return std::nullopt;
}

}  // namespace

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

std::string profile_words(const Profile& p) {
  switch (p.kind) {
    case ProfileKind::kConstant:
      return "constant, " + num(p.speed) + " steps/s";
    case ProfileKind::kStaged:
      return "staged, " + std::to_string(p.stages) + " rates up to " + num(p.speed) + " steps/s" +
             (p.accel > 0 ? ", " + num(p.accel) + " steps/s²" : "");
    case ProfileKind::kTrapezoid:
      return "trapezoid, " + num(p.speed) + " steps/s, " + num(p.accel) + " steps/s²";
    case ProfileKind::kSCurve:
      return "S-curve, " + num(p.speed) + " steps/s, " + num(p.accel) + " steps/s², " + num(p.jerk) + " steps/s³";
  }
  return "";
}

size_t chars(const Command& command) {
  const Result<std::string, Diagnostic> frame = encode(command);
  return frame.ok() ? frame.value().size() : 0;
}

double wire_s(const Command& command, uint32_t baud) {
  const Result<std::string, Diagnostic> frame = encode(command);
  return frame.ok() ? wire_s(frame.value().size() + 1, baud) : 0.0;
}

double MotorPlan::gap_s(size_t i) const {
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
double MotorPlan::gaps_s() const {
  double total = 0;
  for (size_t i = 1; i < pieces.size(); ++i) total += gap_s(i);
  return total;
}
double MotorPlan::duration_s() const {
  if (firmware_ramp) return firmware_ramp_s(steps, pieces[0].delay_us, accel);
  double us = 0;
  for (const Piece& p : pieces) us += static_cast<double>(p.steps) * p.delay_us;
  return us / 1e6 + gaps_s();
}

std::optional<Problem> check_rates(const MotorPlan& plan, const std::string& name) {
  for (const Piece& p : plan.pieces) {
    if (board_rate(p.delay_us) > kMaxRate || p.delay_us < kMinDelayUs) {
      const std::string rate = num(1e6 / p.delay_us) + " steps/s";
      return Problem{
          "at most " + std::to_string(kMaxRate) + " steps/s", rate,
          name + " would step at " + rate + ", faster than the board's " + std::to_string(kMaxRate) + " steps/s"};
    }
    if (p.delay_us > kMaxDelayUs) {
      return Problem{"a rate of at least one step per 89 s", num(1e6 / p.delay_us) + " steps/s",
                     name + " would step slower than the board can time (one step per 89 s)"};
    }
  }
  return std::nullopt;
}

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

Result<MotorPlan, Problem> plan_motor(const Move& move, const MotorConfig& config, uint64_t steps, uint32_t dir,
                                      const LinkTiming& link, double r, const Fit* fit) {
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
      case ProfileKind::kConstant:
        slices.assign(1, Slice{steps, speed});
        break;
      case ProfileKind::kStaged:
        slices = staged(steps, speed, accel, pr.stages);
        break;
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
      case ProfileKind::kSCurve:
        slices = sampled(s_curve(distance, speed, accel, jerk), steps, kSCurveSlices);
        break;
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

}  // namespace hmc::motion::planning
