// Tests of StepScheduler on a virtual clock: a fake StepTimer whose interrupt runs exactly at
// each time the scheduler asks for, and fake StepPins that record every edge with its tick.
// Step times are checked against the ideal profile of ramp.h, computed here independently, from
// the motion itself (pieces of constant acceleration), in long double.
#include "core/step_scheduler.h"

#include <catch2/catch.hpp>

#include <stdint.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

using hmc::fw::MoveEnd;
using hmc::fw::MoveSpec;
using hmc::fw::StepScheduler;
using hmc::fw::StepStatus;
using hmc::hal::Ticks;

namespace {

constexpr Ticks kNever = ~Ticks{0};
constexpr long double kF = 48000000.0L;
// One tick: a step's time is the ideal rounded to the nearest tick, inside a ramp segment from a
// quadratic within ⅜ + 0.07 tick of it, plus the integer K and the 2⁻¹⁶ offsets (ramp.h derives
// < 0.96; the test holds the contract).
constexpr long double kTolerance = 1.0L;

struct Edge {
  Ticks t;
  uint8_t motor;
  bool is_dir;
  bool level;
};

class FakeTimer : public hmc::hal::StepTimer {
 public:
  Ticks now() const override { return clock; }
  void schedule(Ticks when) override { due = when; }
  void wait_until(Ticks when) override { pulse_end = when; }
  Ticks clock = 0;
  Ticks pulse_end = 0;  // the interrupt takes no time; a pulse ends where it waited for
  Ticks due = kNever;
};

class FakePins : public hmc::hal::StepPins {
 public:
  explicit FakePins(const FakeTimer& timer) : timer_(timer) {}
  void set_dir(uint8_t motor, bool reverse) override {
    edges.push_back({timer_.clock, motor, true, reverse});
  }
  void set_step(uint8_t motor, bool high) override {
    edges.push_back({high ? timer_.clock : std::max(timer_.clock, timer_.pulse_end), motor, false, high});
  }
  std::vector<Edge> edges;

 private:
  const FakeTimer& timer_;
};

// The board: the interrupt fires whenever the timer's compare time comes.
struct Bench {
  explicit Bench(Ticks lead = 0) : pins(timer), sched(timer, pins, lead) {}

  // The main loop fills the rings after every interrupt (as often as it could).
  void run_until(Ticks until) {
    sched.fill();
    while (timer.due <= until) {
      timer.clock = std::max(timer.clock, timer.due);
      timer.due = kNever;
      sched.on_step_timer();
      sched.fill();
    }
    timer.clock = std::max(timer.clock, until);
  }
  // Runs until nothing is scheduled, leaving the clock at the last event.
  void run_out() {
    sched.fill();
    while (timer.due != kNever) {
      timer.clock = std::max(timer.clock, timer.due);
      timer.due = kNever;
      sched.on_step_timer();
      sched.fill();
    }
  }
  std::vector<Ticks> rises(uint8_t motor, Ticks after = 0) const {
    std::vector<Ticks> out;
    for (const Edge& e : pins.edges) {
      if (e.motor == motor && !e.is_dir && e.level && e.t >= after) out.push_back(e.t);
    }
    return out;
  }
  std::vector<Edge> dir_edges(uint8_t motor) const {
    std::vector<Edge> out;
    for (const Edge& e : pins.edges) {
      if (e.motor == motor && e.is_dir) out.push_back(e);
    }
    return out;
  }
  bool step_high(uint8_t motor) const {
    for (auto e = pins.edges.rbegin(); e != pins.edges.rend(); ++e) {
      if (e->motor == motor && !e->is_dir) return e->level;
    }
    return false;
  }
  // The step whose rising edge a replacement posted now is anchored at (with no lead).
  uint32_t handover_step(uint8_t motor) const {
    return sched.steps_done(motor) + 2;  // the ring holds two events ahead with no lead
  }

  FakeTimer timer;
  FakePins pins;
  StepScheduler sched;
};

// The ideal motion of ramp.h, built from pieces of constant acceleration: from speed u (steps/s)
// change speed at ±a toward v, hold v, brake at a to rest at position n (n = 0: never brake); a
// move shorter than its stopping distance brakes at once and ends past n.
class Ideal {
 public:
  Ideal(long double accel, long double interval, uint32_t n, long double u = 0) {
    const long double v = kF / interval;
    const long double inf = std::numeric_limits<long double>::infinity();
    if (accel == 0) {
      add(v, 0, n == 0 ? inf : n);
      return;
    }
    if (n != 0 && u * u / (2 * accel) > n) {
      add(u, -accel, u * u / (2 * accel));
      return;
    }
    long double w = v;
    if (n != 0 && u <= v) w = std::min(v, std::sqrt((2 * accel * n + u * u) / 2));
    add(u, w >= u ? accel : -accel, std::fabs(w * w - u * u) / (2 * accel));
    if (n == 0) {
      add(w, 0, inf);
      return;
    }
    const long double cruise = n - std::fabs(w * w - u * u) / (2 * accel) - w * w / (2 * accel);
    add(w, 0, std::max(0.0L, cruise));
    add(w, -accel, w * w / (2 * accel));
  }

  // Ticks from the anchor to step j (position j).
  long double time(uint32_t j) const {
    const Piece& p = find(j);
    const long double dx = j - p.x0;
    if (p.acc == 0) return (p.t0 + dx / p.v0) * kF;
    const long double root = std::sqrt(std::max(0.0L, p.v0 * p.v0 + 2 * p.acc * dx));
    return (p.t0 + (p.v0 + root == 0 ? 0 : 2 * dx / (p.v0 + root))) * kF;
  }
  // Speed (steps/s) at position x.
  long double speed(long double x) const {
    const Piece& p = find(x);
    return std::sqrt(std::max(0.0L, p.v0 * p.v0 + 2 * p.acc * (x - p.x0)));
  }
  // Steps the motion makes.
  uint32_t steps() const { return static_cast<uint32_t>(std::floor(end_ + 1e-9L)); }

 private:
  struct Piece {
    long double x0, t0, v0, acc, len;
  };
  void add(long double v0, long double acc, long double len) {
    if (len <= 0) return;
    pieces_.push_back({end_, t_, v0, acc, len});
    if (acc == 0) {
      t_ += len / v0;
    } else {
      t_ += (std::sqrt(std::max(0.0L, v0 * v0 + 2 * acc * len)) - v0) / acc;
    }
    end_ += len;
  }
  const Piece& find(long double x) const {
    for (const Piece& p : pieces_) {
      if (x <= p.x0 + p.len) return p;
    }
    return pieces_.back();
  }
  std::vector<Piece> pieces_;
  long double end_ = 0;
  long double t_ = 0;
};

// The anchor of a move from rest started at `now` (as step_scheduler.h says: its first step at
// least kPickupTicks after `now`).
Ticks anchor_after(Ticks now, uint32_t interval, uint32_t accel) {
  using hmc::fw::kPickupAccel;
  using hmc::fw::kPickupTicks;
  const uint32_t first = accel == 0 ? interval : accel <= kPickupAccel ? kPickupTicks : 0;
  return now + (first < kPickupTicks ? kPickupTicks - first : 0);
}

// Largest |actual − ideal| over the steps, with the anchor at tick `anchor`.
long double worst_error(const std::vector<Ticks>& rises, Ticks anchor, const Ideal& ideal) {
  long double worst = 0;
  for (size_t i = 0; i < rises.size(); ++i) {
    const long double ideal_tick = static_cast<long double>(anchor) + ideal.time(static_cast<uint32_t>(i + 1));
    worst = std::max(worst, std::fabs(static_cast<long double>(rises[i]) - ideal_tick));
  }
  return worst;
}

// The DRV8711's timing on every motor: STEP high and low ≥ 2 µs, DIR changed only with STEP
// low and ≥ 200 ns from any STEP edge.
void check_pulses(const Bench& bench) {
  for (uint8_t motor = 1; motor <= 3; ++motor) {
    bool high = false;
    Ticks last_step_edge = 0;
    bool any = false;
    Ticks last_dir = 0;
    bool dir_seen = false;
    for (const Edge& e : bench.pins.edges) {
      if (e.motor != motor) continue;
      if (e.is_dir) {
        INFO("motor " << int{motor} << " DIR at " << e.t);
        REQUIRE(!high);
        if (any) REQUIRE(e.t >= last_step_edge + 10);
        last_dir = e.t;
        dir_seen = true;
        continue;
      }
      INFO("motor " << int{motor} << " STEP " << e.level << " at " << e.t);
      REQUIRE(e.level != high);
      if (any) REQUIRE(e.t >= last_step_edge + (e.level ? 96u : 96u));
      if (!e.level) REQUIRE(e.t == last_step_edge + hmc::fw::kStepHighTicks);
      if (dir_seen) REQUIRE(e.t >= last_dir + 10);
      high = e.level;
      last_step_edge = e.t;
      any = true;
    }
  }
  REQUIRE(bench.sched.clamped_edges() == 0);
  REQUIRE(bench.sched.starved_events() == 0);
}

MoveSpec move(bool reverse, uint32_t steps, uint32_t interval, uint32_t accel,
              uint16_t microstep = 1) {
  return MoveSpec{reverse, microstep, steps, interval, accel};
}

void report(const char* what, long double worst) {
  std::printf("  %-58s worst step error %.4Lf ticks\n", what, worst);
}

}  // namespace

TEST_CASE("constant rate: 10 000 steps at 100 us take exactly 1.000 s") {
  Bench bench;
  bench.run_until(1000);
  REQUIRE(bench.sched.start(1, move(false, 10000, 4800, 0, 16)) == StepStatus::kOk);
  CHECK(bench.sched.is_running(1));
  bench.run_out();
  const std::vector<Ticks> rises = bench.rises(1);
  REQUIRE(rises.size() == 10000);
  // Anchor 1000; step j at 1000 + j·4800: the last one 48 000 000 ticks (1.000 s) after the
  // start, 9 999 intervals after the first.
  CHECK(rises.front() == 1000 + 4800);
  CHECK(rises.back() == 1000 + 48000000);
  CHECK(rises.back() - rises.front() == 9999u * 4800u);
  for (size_t i = 0; i < rises.size(); ++i) REQUIRE(rises[i] == 1000 + 4800 * (i + 1));
  CHECK(bench.sched.position(1) == 10000 * 16);
  CHECK(bench.sched.steps_done(1) == 10000);
  CHECK(!bench.sched.is_running(1));
  CHECK(bench.sched.finished(1) == 1);
  CHECK(bench.sched.last_end(1) == MoveEnd::kCompleted);
  CHECK(bench.sched.interval(1) == 0);
  check_pulses(bench);
  report("constant 10 000 x 100 us", 0);
}

TEST_CASE("three motors at 100, 130 and 177 us each step on their own grid") {
  Bench bench;
  const uint32_t intervals[3] = {4800, 6240, 8496};
  const uint32_t counts[3] = {3000, 2500, 1700};
  const Ticks anchors[3] = {0, 0, 2413};
  REQUIRE(bench.sched.start(1, move(false, counts[0], intervals[0], 0)) == StepStatus::kOk);
  REQUIRE(bench.sched.start(2, move(true, counts[1], intervals[1], 0)) == StepStatus::kOk);
  bench.run_until(2413);
  REQUIRE(bench.sched.start(3, move(false, counts[2], intervals[2], 0, 4)) == StepStatus::kOk);
  bench.run_until(100000);
  CHECK(bench.sched.rate(1) == 10000);
  CHECK(bench.sched.interval(2) == 6240);
  bench.run_out();
  int together = 0;
  for (uint8_t m = 0; m < 3; ++m) {
    const std::vector<Ticks> rises = bench.rises(static_cast<uint8_t>(m + 1));
    REQUIRE(rises.size() == counts[m]);
    for (size_t i = 0; i < rises.size(); ++i) {
      REQUIRE(rises[i] == anchors[m] + intervals[m] * (i + 1));
      if (m == 0 && (rises[i] % intervals[1]) == 0 && rises[i] <= 2500ull * intervals[1]) ++together;
    }
  }
  CHECK(together > 10);  // motors 1 and 2 rise on the same tick every 62 400 ticks
  CHECK(bench.sched.position(1) == 3000 * 256);
  CHECK(bench.sched.position(2) == -2500 * 256);
  CHECK(bench.sched.position(3) == 1700 * 64);
  check_pulses(bench);
}

TEST_CASE("ramped moves from rest: every step within one tick of the ideal") {
  struct Case {
    uint32_t accel, interval, steps;
  };
  const Case cases[] = {
      {1000, 4800, 10000},     // trapezoid, x_v = 50 000 > N/2: triangle actually
      {1000, 4800, 200000},    // trapezoid, x_v = 50 000 exactly
      {2500, 1000, 5000},      // triangle
      {2500, 1000, 1000000},   // long cruise
      {100000, 240, 50000},    // fastest rate: 200 000 steps/s
      {1000000, 240, 100000},  // hard acceleration
      {7, 480000, 10},         // slow: 100 steps/s at 7 steps/s², triangle over seconds
      {12345, 3333, 777},
      {333, 10007, 5000},
      {1000, 4800, 1},
      {1000, 4800, 2},
      {1000, 4800, 3},
      {50, 48000, 1},
      {2000000000, 240, 4},
  };
  // Lead 0: a step or two a top-up; 2 ms and 10 ms: ramp segments up to 256 steps.
  const Ticks lead = GENERATE(Ticks{0}, StepScheduler::kDefaultHandoverLead, Ticks{480000});
  long double overall = 0;
  for (const Case& c : cases) {
    Bench bench(lead);
    bench.run_until(777);
    INFO("a " << c.accel << " I " << c.interval << " N " << c.steps);
    REQUIRE(bench.sched.start(1, move(false, c.steps, c.interval, c.accel)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    REQUIRE(rises.size() == c.steps);
    const long double worst =
        worst_error(rises, anchor_after(777, c.interval, c.accel), Ideal(c.accel, c.interval, c.steps));
    CHECK(worst <= kTolerance);
    overall = std::max(overall, worst);
    CHECK(bench.sched.position(1) == static_cast<int32_t>(c.steps * 256));
    CHECK(bench.sched.last_end(1) == MoveEnd::kCompleted);
    check_pulses(bench);
  }
  report("ramps from rest (14 cases)", overall);
}

TEST_CASE("random ramped moves from rest stay within one tick") {
  std::mt19937_64 rng(11);
  const Ticks lead = GENERATE(Ticks{0}, StepScheduler::kDefaultHandoverLead, Ticks{480000});
  long double overall = 0;
  int moves = 0;
  for (int i = 0; i < 300; ++i) {
    const auto accel = static_cast<uint32_t>(200 + rng() % 3000000);
    const auto interval = static_cast<uint32_t>(240 + rng() % 100000);
    const auto steps = static_cast<uint32_t>(1 + rng() % 4000);
    Bench bench(lead);
    const StepStatus status = bench.sched.start(2, move(rng() % 2 == 0, steps, interval, accel));
    if (status == StepStatus::kRampTooLong) continue;
    REQUIRE(status == StepStatus::kOk);
    ++moves;
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(2);
    REQUIRE(rises.size() == steps);
    const long double worst = worst_error(rises, 0, Ideal(accel, interval, steps));
    INFO("a " << accel << " I " << interval << " N " << steps);
    REQUIRE(worst <= kTolerance);
    overall = std::max(overall, worst);
    check_pulses(bench);
  }
  CHECK(moves > 250);
  report("300 random ramps from rest", overall);
}

TEST_CASE("three ramped motors at once keep their own profiles") {
  Bench bench(GENERATE(Ticks{0}, StepScheduler::kDefaultHandoverLead));
  REQUIRE(bench.sched.start(1, move(false, 30000, 4800, 20000)) == StepStatus::kOk);
  REQUIRE(bench.sched.start(2, move(true, 25000, 6240, 15000, 8)) == StepStatus::kOk);
  REQUIRE(bench.sched.start(3, move(false, 9000, 8496, 5000, 256)) == StepStatus::kOk);
  bench.run_out();
  long double overall = 0;
  overall = std::max(overall, worst_error(bench.rises(1), 0, Ideal(20000, 4800, 30000)));
  overall = std::max(overall, worst_error(bench.rises(2), 0, Ideal(15000, 6240, 25000)));
  overall = std::max(overall, worst_error(bench.rises(3), 0, Ideal(5000, 8496, 9000)));
  CHECK(overall <= kTolerance);
  CHECK(bench.sched.position(1) == 30000 * 256);
  CHECK(bench.sched.position(2) == -25000 * 32);
  CHECK(bench.sched.position(3) == 9000);
  check_pulses(bench);
  report("three ramped motors together", overall);
}

TEST_CASE("positions count 256/m per step whatever the microstep") {
  Bench bench;
  struct Leg {
    bool reverse;
    uint16_t microstep;
    uint32_t steps;
    uint32_t accel;
  };
  const Leg legs[] = {{false, 1, 10, 0},   {true, 4, 7, 0},      {false, 256, 300, 0},
                      {true, 16, 33, 5000}, {false, 2, 1001, 2000}, {true, 128, 4096, 90000}};
  int32_t expected = 0;
  for (const Leg& leg : legs) {
    REQUIRE(bench.sched.start(2, move(leg.reverse, leg.steps, 2400, leg.accel, leg.microstep)) ==
            StepStatus::kOk);
    bench.run_out();
    const int32_t units = static_cast<int32_t>(leg.steps) * (256 / leg.microstep);
    expected += leg.reverse ? -units : units;
    CHECK(bench.sched.position(2) == expected);
    CHECK(bench.sched.steps_done(2) == leg.steps);
  }
  CHECK(expected == 2560 - 448 + 300 - 528 + 128128 - 8192);
  CHECK(bench.sched.finished(2) == 6);
  CHECK(bench.sched.set_position(2, 0));
  CHECK(bench.sched.position(2) == 0);
  check_pulses(bench);
}

TEST_CASE("stop with acceleration brakes at it to rest") {
  const uint32_t a = 20000, interval = 2400;  // 20 000 steps/s, reached in 1 s over 10 000 steps
  SECTION("while cruising") {
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(72000000);  // 1.5 s
    const uint32_t h = bench.handover_step(1);
    REQUIRE(bench.sched.stop(1) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    const Ideal before(a, interval, 0);
    REQUIRE(rises.size() > h);
    CHECK(worst_error(std::vector<Ticks>(rises.begin(), rises.begin() + h), 0, before) <= kTolerance);
    const long double u = before.speed(h);
    const Ideal braking(a, interval, 1, u);  // any target shorter than the stop: brakes at once
    const std::vector<Ticks> after(rises.begin() + h, rises.end());
    CHECK(after.size() == 10000);  // v²/2a
    const long double worst = worst_error(after, rises[h - 1], braking);
    CHECK(worst <= kTolerance);
    CHECK(bench.sched.last_end(1) == MoveEnd::kStopped);
    CHECK(!bench.sched.is_running(1));
    check_pulses(bench);
    report("stop while cruising (10 000 braking steps)", worst);
  }
  SECTION("while accelerating: as many steps again") {
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(14400000);  // 0.3 s
    const uint32_t h = bench.handover_step(1);
    REQUIRE(bench.sched.stop(1) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    CHECK(rises.size() == 2 * h);
    const Ideal before(a, interval, 0);
    const Ideal braking(a, interval, 1, before.speed(h));
    const long double worst = worst_error(std::vector<Ticks>(rises.begin() + h, rises.end()), rises[h - 1], braking);
    CHECK(worst <= kTolerance);
    CHECK(bench.sched.position(1) == static_cast<int32_t>(2 * h * 256));
    check_pulses(bench);
    report("stop while accelerating", worst);
  }
  SECTION("with a lead, the stop is planned ahead and still exact") {
    Bench bench(48000);
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(72000000);
    const uint32_t done = bench.sched.steps_done(1);
    REQUIRE(bench.sched.stop(1) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    const size_t h = rises.size() - 10000;  // the stop brakes over exactly 10 000 steps
    // The ring reaches the lead (1 ms, 20 steps at 20 000 steps/s) and at most half a lead
    // more (a cruise is pushed in runs of half the lead).
    CHECK(h >= done + 20);
    CHECK(h <= done + 32);
    const long double worst = worst_error(std::vector<Ticks>(rises.begin() + static_cast<long>(h), rises.end()),
                                          rises[h - 1], Ideal(a, interval, 1, kF / interval));
    CHECK(worst <= kTolerance);
  }
  SECTION("with a lead, while accelerating (the ring holds ramp segments): as many steps again") {
    Bench bench(StepScheduler::kDefaultHandoverLead);
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(14400000);  // 0.3 s
    const uint32_t done = bench.sched.steps_done(1);
    REQUIRE(bench.sched.stop(1) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    REQUIRE(rises.size() % 2 == 0);
    const size_t h = rises.size() / 2;
    CHECK(h >= done + 2);
    const Ideal before(a, interval, 0);
    CHECK(worst_error(std::vector<Ticks>(rises.begin(), rises.begin() + static_cast<long>(h)), 0,
                      before) <= kTolerance);
    const Ideal braking(a, interval, 1, before.speed(static_cast<uint32_t>(h)));
    const std::vector<Ticks> after(rises.begin() + static_cast<long>(h), rises.end());
    const long double worst = worst_error(after, rises[h - 1], braking);
    CHECK(worst <= kTolerance);
    check_pulses(bench);
    report("stop while accelerating, 2 ms lead", worst);
  }
}

TEST_CASE("stop at constant rate and halt leave no further rising edge") {
  SECTION("stop at constant rate") {
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, 4800, 0)) == StepStatus::kOk);
    bench.run_until(100000);  // between edges: last rise at 96 000, fall at 96 096
    REQUIRE(bench.sched.stop(1) == StepStatus::kOk);
    bench.run_until(1000000);
    CHECK(bench.rises(1).size() == 20);
    CHECK(bench.rises(1, 100000).empty());
    CHECK(bench.sched.last_end(1) == MoveEnd::kStopped);
    check_pulses(bench);
  }
  SECTION("halt while ramping: every pulse already begun is whole, nothing more") {
    // With a lead the halt drops ramp segments and one half played.
    Bench bench(GENERATE(Ticks{0}, StepScheduler::kDefaultHandoverLead));
    REQUIRE(bench.sched.start(1, move(false, 0, 2400, 50000)) == StepStatus::kOk);
    bench.run_until(4800000);
    const std::vector<Ticks> before = bench.rises(1);
    const Ticks last = before.back();
    bench.run_until(last + 50);  // between steps: STEP ends inside the step's own interrupt
    REQUIRE(!bench.step_high(1));
    bench.sched.halt(1);
    bench.run_until(last + 48000000);
    CHECK(bench.rises(1).size() == before.size());
    CHECK(!bench.step_high(1));
    CHECK(bench.pins.edges.back().t == last + hmc::fw::kStepHighTicks);
    CHECK(bench.sched.last_end(1) == MoveEnd::kHalted);
    CHECK(!bench.sched.is_running(1));
    CHECK(bench.sched.starved_events() == 0);
    check_pulses(bench);
    // Motion starts again from rest, nothing of the halted ramp left in the lane.
    REQUIRE(bench.sched.start(1, move(false, 3000, 2400, 50000)) == StepStatus::kOk);
    const Ticks anchor = bench.timer.clock;
    bench.run_out();
    CHECK(bench.rises(1, anchor).size() == 3000);
    CHECK(worst_error(bench.rises(1, anchor), anchor, Ideal(50000, 2400, 3000)) <= kTolerance);
    check_pulses(bench);
  }
  SECTION("halt_all stops three motors at once, a rising edge due on the same tick included") {
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, 4800, 0)) == StepStatus::kOk);
    REQUIRE(bench.sched.start(2, move(true, 50000, 2400, 300000)) == StepStatus::kOk);
    REQUIRE(bench.sched.start(3, move(false, 0, 9600, 1000, 32)) == StepStatus::kOk);
    bench.run_until(960000 - 1);
    bench.timer.clock = 960000;  // motor 1's 200th step is due now; the halt comes first
    bench.sched.halt_all();
    bench.run_until(96000000);
    for (uint8_t m = 1; m <= 3; ++m) {
      CHECK(bench.rises(m, 960000).empty());
      CHECK(!bench.sched.is_running(m));
      CHECK(bench.sched.last_end(m) == MoveEnd::kHalted);
    }
    CHECK(bench.rises(1).size() == 199);
    check_pulses(bench);
    // Motion starts again from rest.
    REQUIRE(bench.sched.start(2, move(false, 100, 2400, 300000)) == StepStatus::kOk);
    const Ticks anchor = bench.timer.clock;
    bench.run_out();
    CHECK(worst_error(bench.rises(2, anchor), anchor, Ideal(300000, 2400, 100)) <= kTolerance);
    check_pulses(bench);
  }
}

TEST_CASE("a new move in the same direction continues from the current speed") {
  struct Case {
    const char* name;
    uint32_t a1, i1;   // first move (endless)
    Ticks at;          // when the second comes
    uint32_t a2, i2, n2;
    uint16_t micro2;
  };
  const Case cases[] = {
      {"faster, from cruise", 20000, 4800, 96000000, 20000, 2400, 40000, 1},
      {"slower, from cruise", 20000, 2400, 96000000, 20000, 9600, 30000, 1},
      {"while accelerating", 5000, 2400, 24000000, 5000, 4800, 8000, 1},
      {"new acceleration", 20000, 2400, 96000000, 12000, 1200, 50000, 1},
      {"new microstep (same speed in full steps)", 20000, 4800, 96000000, 80000, 1200, 30000, 4},
      {"too short to stop: brakes past the target", 20000, 2400, 96000000, 20000, 2400, 100, 1},
      {"triangle from speed", 20000, 4800, 96000000, 20000, 1200, 3000, 1},
      {"run until stopped again", 20000, 4800, 96000000, 20000, 3000, 0, 1},
      // Down to the slowest rate a move may ask for (89 s a step): the cruise's first step
      // must not be computed from a cancellation of two terms of 10^12 ticks.
      {"slower, to 89 s a step", 20000, 2400, 96000000, 20000, 4272000000u, 10004, 1},
      {"slower, to 89 s a step, run until stopped", 250, 12000, 480000000, 250, 4272000000u, 0, 1},
  };
  long double overall = 0;
  for (const Case& c : cases) {
    INFO(c.name);
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, c.i1, c.a1)) == StepStatus::kOk);
    bench.run_until(c.at);
    const uint32_t h = bench.handover_step(1);
    REQUIRE(bench.sched.start(1, move(false, c.n2, c.i2, c.a2, c.micro2)) == StepStatus::kOk);
    if (c.n2 == 0) {
      bench.run_until(c.at + 480000000 + 3 * Ticks{c.i2});  // a few cruise steps
      bench.sched.halt(1);
    }
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    REQUIRE(rises.size() > h);
    const Ideal first(c.a1, c.i1, 0);
    CHECK(worst_error(std::vector<Ticks>(rises.begin(), rises.begin() + h), 0, first) <= kTolerance);
    // The speed at step h, in the new move's steps.
    const long double u = first.speed(h) * c.micro2;
    const Ideal second(c.a2, c.i2, c.n2, u);
    const std::vector<Ticks> after(rises.begin() + h, rises.end());
    if (c.n2 != 0) CHECK(after.size() == second.steps());
    if (c.n2 != 0 && u * u / (2.0L * c.a2) <= c.n2) CHECK(after.size() == c.n2);
    const long double worst = worst_error(after, rises[h - 1], second);
    CHECK(worst <= kTolerance);
    overall = std::max(overall, worst);
    check_pulses(bench);
  }
  report("replacements, same direction (10 cases)", overall);
  // With a lead the ring holds ramp segments: the handover comes later (at a step the test does
  // not know ahead), and the move still ends exactly n2 steps after it, every step on the ideal.
  long double with_lead = 0;
  for (const Case& c : cases) {
    if (c.n2 == 0 || c.n2 < 1000) continue;
    INFO(c.name << ", 2 ms lead");
    Bench bench(StepScheduler::kDefaultHandoverLead);
    REQUIRE(bench.sched.start(1, move(false, 0, c.i1, c.a1)) == StepStatus::kOk);
    bench.run_until(c.at);
    const uint32_t done = bench.sched.steps_done(1);
    REQUIRE(bench.sched.start(1, move(false, c.n2, c.i2, c.a2, c.micro2)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    REQUIRE(rises.size() > c.n2 + done);
    const size_t h = rises.size() - c.n2;
    CHECK(h >= done + 2);
    CHECK(h <= done + 2 + 2 * (StepScheduler::kDefaultHandoverLead / 240));
    const Ideal first(c.a1, c.i1, 0);
    CHECK(worst_error(std::vector<Ticks>(rises.begin(), rises.begin() + static_cast<long>(h)), 0,
                      first) <= kTolerance);
    const Ideal second(c.a2, c.i2, c.n2, first.speed(static_cast<uint32_t>(h)) * c.micro2);
    REQUIRE(second.steps() == c.n2);
    const long double worst =
        worst_error(std::vector<Ticks>(rises.begin() + static_cast<long>(h), rises.end()),
                    rises[h - 1], second);
    CHECK(worst <= kTolerance);
    with_lead = std::max(with_lead, worst);
    check_pulses(bench);
  }
  report("replacements, same direction, 2 ms lead", with_lead);
}

TEST_CASE("a constant-rate move replaced keeps stepping from its last step") {
  Bench bench;
  REQUIRE(bench.sched.start(3, move(false, 0, 4800, 0)) == StepStatus::kOk);
  bench.run_until(100000);
  const uint32_t h = bench.handover_step(3);
  REQUIRE(bench.sched.start(3, move(false, 50, 7000, 0)) == StepStatus::kOk);
  bench.run_out();
  const std::vector<Ticks> rises = bench.rises(3);
  REQUIRE(rises.size() == h + 50);
  for (uint32_t j = 1; j <= 50; ++j) CHECK(rises[h - 1 + j] == rises[h - 1] + 7000 * j);
  check_pulses(bench);
}

TEST_CASE("a reverse move brakes to rest, turns DIR, then starts from rest") {
  SECTION("with acceleration") {
    Bench bench;
    const uint32_t a = 20000, interval = 2400;
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(72000000);
    const uint32_t h = bench.handover_step(1);
    REQUIRE(bench.sched.start(1, move(true, 500, 4800, 40000)) == StepStatus::kOk);
    CHECK(bench.sched.is_running(1));
    bench.run_out();
    const std::vector<Edge> dirs = bench.dir_edges(1);
    REQUIRE(dirs.size() == 2);  // forward at the start, then reverse
    CHECK(!dirs[0].level);
    CHECK(dirs[1].level);
    const std::vector<Ticks> forward = bench.rises(1);
    const std::vector<Ticks> braking(forward.begin() + h, forward.end() - 500);
    CHECK(braking.size() == 10000);
    CHECK(worst_error(braking, forward[h - 1], Ideal(a, interval, 1, kF / interval)) <= kTolerance);
    const std::vector<Ticks> back = bench.rises(1, dirs[1].t);
    REQUIRE(back.size() == 500);
    // The reverse move starts at the ideal rest time of the braking (here the last braking
    // step itself), once that step's pulse has ended and DIR may change.
    const long double rest = forward[h - 1] + Ideal(a, interval, 1, kF / interval).time(10000);
    CHECK(std::fabs(static_cast<long double>(braking.back()) - rest) <= kTolerance);
    CHECK(dirs[1].t == braking.back() + hmc::fw::kStepHighTicks + 10);
    const long double worst = worst_error(back, dirs[1].t, Ideal(40000, 4800, 500));
    CHECK(worst <= kTolerance);
    CHECK(bench.sched.position(1) == static_cast<int32_t>((h + 10000 - 500) * 256));
    CHECK(bench.sched.finished(1) == 1);
    check_pulses(bench);
    report("reverse: the new move from rest", worst);
  }
  SECTION("at constant rate: stops at once") {
    Bench bench;
    REQUIRE(bench.sched.start(2, move(false, 0, 4800, 0)) == StepStatus::kOk);
    bench.run_until(96000 + 60);  // STEP high for the 20th step
    REQUIRE(bench.sched.start(2, move(true, 30, 4800, 0)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Edge> dirs = bench.dir_edges(2);
    REQUIRE(dirs.size() == 2);
    CHECK(dirs[1].t == 96000 + hmc::fw::kStepHighTicks + 10);  // after the pulse ends, plus the DIR guard
    const std::vector<Ticks> rises = bench.rises(2);
    REQUIRE(rises.size() == 50);
    for (uint32_t j = 1; j <= 30; ++j) CHECK(rises[19 + j] == dirs[1].t + 4800 * j);
    CHECK(bench.sched.position(2) == (20 - 30) * 256);
    check_pulses(bench);
  }
  SECTION("a second reverse while braking only changes what follows") {
    Bench bench;
    REQUIRE(bench.sched.start(1, move(false, 0, 2400, 20000)) == StepStatus::kOk);
    bench.run_until(72000000);
    REQUIRE(bench.sched.start(1, move(true, 500, 4800, 40000)) == StepStatus::kOk);
    bench.run_until(72000000 + 4800000);
    REQUIRE(bench.sched.start(1, move(true, 200, 4800, 40000)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Edge> dirs = bench.dir_edges(1);
    REQUIRE(dirs.size() == 2);
    CHECK(bench.rises(1, dirs[1].t).size() == 200);
    CHECK(worst_error(bench.rises(1, dirs[1].t), dirs[1].t, Ideal(40000, 4800, 200)) <= kTolerance);
    check_pulses(bench);
  }
}

TEST_CASE("queries and refusals") {
  Bench bench;
  CHECK(bench.sched.start(0, move(false, 1, 4800, 0)) == StepStatus::kBadMotor);
  CHECK(bench.sched.start(4, move(false, 1, 4800, 0)) == StepStatus::kBadMotor);
  CHECK(bench.sched.start(1, move(false, 1, 4800, 0, 3)) == StepStatus::kBadMicrostep);
  CHECK(bench.sched.start(1, move(false, 1, 100, 0)) == StepStatus::kIntervalShort);
  CHECK(bench.sched.start(1, move(false, 1, 4800, 1)) == StepStatus::kRampTooLong);
  CHECK(!bench.sched.is_running(1));
  CHECK(bench.sched.stop(1) == StepStatus::kOk);  // nothing to stop
  REQUIRE(bench.sched.start(1, move(false, 0, 2400, 20000)) == StepStatus::kOk);
  CHECK(!bench.sched.set_position(1, 5));
  bench.run_until(72000000);
  CHECK(bench.sched.rate(1) == 20000);
  CHECK(bench.sched.interval(1) == 2400);
  CHECK(bench.sched.is_running(1));
  const uint32_t done = bench.sched.steps_done(1);
  CHECK(done == 20000);  // 10 000 ramping in 1 s, then 0.5 s at 20 000 steps/s
  CHECK(bench.sched.finished(1) == 0);
  // A start that is replaced before the interrupt takes it never runs.
  REQUIRE(bench.sched.start(2, move(false, 10, 4800, 0)) == StepStatus::kOk);
  REQUIRE(bench.sched.start(2, move(true, 3, 4800, 0)) == StepStatus::kOk);
  bench.run_until(73000000);
  CHECK(bench.sched.position(2) == -3 * 256);
  CHECK(bench.sched.finished(2) == 1);
  CHECK(bench.sched.last_end(2) == MoveEnd::kCompleted);
  // A start cancelled by stop() before the interrupt takes it neither.
  REQUIRE(bench.sched.start(3, move(false, 10, 4800, 0)) == StepStatus::kOk);
  REQUIRE(bench.sched.stop(3) == StepStatus::kOk);
  bench.run_until(74000000);
  CHECK(bench.rises(3).empty());
  CHECK(!bench.sched.is_running(3));
}

TEST_CASE("the fastest and slowest rates, and three motors at the spec's 20 us for a second") {
  SECTION("three motors at 20 us: 50 000 steps each in one second, every one on its grid") {
    Bench bench(StepScheduler::kDefaultHandoverLead);
    for (uint8_t m = 1; m <= 3; ++m) {
      REQUIRE(bench.sched.start(m, move(false, 0, 960, 0, 8)) == StepStatus::kOk);
    }
    const Ticks anchor = anchor_after(0, 960, 0);  // 100 µs before the first step
    bench.run_until(anchor + 48000000 + 100);
    for (uint8_t m = 1; m <= 3; ++m) {
      const std::vector<Ticks> rises = bench.rises(m);
      REQUIRE(rises.size() >= 50000);
      for (size_t i = 0; i < 50000; ++i) REQUIRE(rises[i] == anchor + 960 * (i + 1));
      CHECK(bench.rises(m, anchor + 960).size() - bench.rises(m, anchor + 960 + 48000000).size() ==
            50000);
    }
    bench.sched.halt_all();
    bench.run_out();
    check_pulses(bench);
  }
  SECTION("the shortest interval (5 us) on three motors at once, ramping and constant") {
    Bench bench(StepScheduler::kDefaultHandoverLead);
    REQUIRE(bench.sched.start(1, move(false, 20000, 240, 0)) == StepStatus::kOk);
    REQUIRE(bench.sched.start(2, move(true, 20000, 240, 4000000)) == StepStatus::kOk);
    REQUIRE(bench.sched.start(3, move(false, 20000, 240, 1000000, 256)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> r1 = bench.rises(1);
    REQUIRE(r1.size() == 20000);
    const Ticks anchor = anchor_after(0, 240, 0);
    for (size_t i = 0; i < r1.size(); ++i) REQUIRE(r1[i] == anchor + 240 * (i + 1));
    CHECK(worst_error(bench.rises(2), 0, Ideal(4000000, 240, 20000)) <= kTolerance);
    CHECK(worst_error(bench.rises(3), 0, Ideal(1000000, 240, 20000)) <= kTolerance);
    check_pulses(bench);
  }
  SECTION("the slowest (89 s a step): waits without a step between, steps exact") {
    Bench bench;
    const uint32_t interval = 4272000000u;  // 89 s, beyond 2^31 ticks
    REQUIRE(bench.sched.start(3, move(false, 3, interval, 0)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(3);
    REQUIRE(rises.size() == 3);
    for (size_t i = 0; i < 3; ++i) CHECK(rises[i] == Ticks{interval} * (i + 1));
    CHECK(bench.sched.position(3) == 3 * 256);
    CHECK(bench.sched.last_end(3) == MoveEnd::kCompleted);
    check_pulses(bench);
  }
}

TEST_CASE("replacements at every point of a cruise run stay on the ideal profile") {
  // With a lead the ring takes a cruise in runs of up to the lead's steps; a replacement may come
  // at any step of a run (its first, last, or between) and must still hand over exactly.
  const uint32_t interval = 2400;
  const uint32_t a = 20000;
  for (Ticks at = 60000000; at < 60000000 + 24 * interval; at += interval / 2 + 7) {
    Bench bench(48000);
    REQUIRE(bench.sched.start(1, move(false, 0, interval, a)) == StepStatus::kOk);
    bench.run_until(at);
    REQUIRE(bench.sched.start(1, move(false, 40000, 1200, a)) == StepStatus::kOk);
    bench.run_out();
    const std::vector<Ticks> rises = bench.rises(1);
    REQUIRE(rises.size() > 40000);
    const size_t h = rises.size() - 40000;  // the replacement makes exactly its 40 000 steps
    INFO("replaced at tick " << at << ", handover step " << h);
    const Ideal before(a, interval, 0);
    CHECK(worst_error(std::vector<Ticks>(rises.begin(), rises.begin() + static_cast<long>(h)), 0, before) <= kTolerance);
    const Ideal after(a, 1200, 40000, before.speed(static_cast<long double>(h)));
    CHECK(worst_error(std::vector<Ticks>(rises.begin() + static_cast<long>(h), rises.end()), rises[h - 1], after) <= kTolerance);
    check_pulses(bench);
  }
}

TEST_CASE("a replacement replaced before its handover step: only the last one plays") {
  // Found by the controller fuzzer: a motor braking for a reverse holds two profiles (the brake
  // and the move after it), a move in the braking direction waits for its handover as a third;
  // a fourth command before that handover must still find room for its two.
  const uint32_t a = 20000;
  Bench bench(48000);
  REQUIRE(bench.sched.start(1, move(false, 0, 2400, a)) == StepStatus::kOk);
  bench.run_until(60000000);
  REQUIRE(bench.sched.start(1, move(true, 100, 2400, a)) == StepStatus::kOk);
  bench.run_until(60000000 + 4800000);  // braking for the reverse
  REQUIRE(bench.sched.start(1, move(false, 40000, 1200, a)) == StepStatus::kOk);
  REQUIRE(bench.sched.start(1, move(false, 40000, 1200, a)) == StepStatus::kOk);
  bench.run_out();
  CHECK(bench.dir_edges(1).size() == 1);  // never reversed
  const std::vector<Ticks> rises = bench.rises(1);
  REQUIRE(rises.size() > 40000);
  CHECK(bench.sched.steps_done(1) == 40000);
  CHECK(bench.sched.position(1) == static_cast<int32_t>(rises.size() * 256));
  CHECK(bench.sched.last_end(1) == MoveEnd::kCompleted);
  check_pulses(bench);
}
