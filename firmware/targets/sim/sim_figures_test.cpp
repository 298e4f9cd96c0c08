// The timing figures of the simulated board, measured from its JSON-lines trace (not from the
// scheduler's state): every check reads the "rx" line time of the command and the "step" lines,
// as any tool reading `hmc-sim --trace` would. Each test prints the figure it measured.
//  - a 10 000-step move at 100 µs/step takes 1.000 s ± one tick;
//  - three motors at three rates, together: every step within one tick of its own schedule;
//  - a ramped move: every step within one tick of the ideal trapezoid, computed here in long
//    double from the motion (x = a·t²/2 up, cruise at v, the mirror image down);
//  - the emergency switch: no step edge after the event.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "sim_board.h"

using json = nlohmann::json;
using hmc::sim::SimBoard;
using hmc::sim::SimConfig;
using hmc::sim::Ticks;

namespace {

constexpr long double kF = 48000000.0L;

std::string frame(const std::vector<uint32_t>& values, const char* name = "STM") {
  std::string out = "STX#" + std::to_string(values.size() + 1) + "#" + name;
  uint32_t sum = 0;
  for (const uint32_t v : values) {
    out += "#" + std::to_string(v);
    sum += v;
  }
  return out + "#" + std::to_string(sum % 256) + "#ETX\n";
}

struct Trace {
  std::map<std::string, Ticks> rx;                 // line → time it was received
  std::map<int, std::vector<Ticks>> steps;         // motor → rising-edge times
  Ticks emergency = 0;
};

Trace read_trace(const std::string& text) {
  Trace trace;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const json event = json::parse(line);
    const std::string ev = event.at("ev");
    const Ticks t = event.at("t");
    if (ev == "rx") trace.rx[event.at("line")] = t;
    if (ev == "step") trace.steps[event.at("motor").get<int>()].push_back(t);
    if (ev == "emergency" && event.at("pressed").get<bool>()) trace.emergency = t;
  }
  return trace;
}

SimBoard& quiet_board(SimConfig config, std::ostringstream& out, std::unique_ptr<SimBoard>& holder) {
  config.options.self_test = false;
  holder = std::make_unique<SimBoard>(config);
  holder->set_trace(&out);
  holder->boot();
  return *holder;
}

std::string line_of(const std::string& f) { return f.substr(0, f.size() - 1); }

// Ideal step times from rest for N steps at interval I ticks and acceleration a (steps/s²):
// the motion reaches position j at t_j (ramp.h defines the same profile; this is written from
// the physics, not from that code).
std::vector<long double> ideal_trapezoid(uint32_t n, uint32_t interval, uint32_t accel) {
  const long double v = kF / interval;     // steps/s
  const long double a = accel;
  const long double x_v = v * v / (2 * a); // steps to reach v
  std::vector<long double> t(n + 1);
  if (2 * x_v <= n) {
    const long double t_v = v / a;
    const long double total = n / v + t_v;
    for (uint32_t j = 1; j <= n; ++j) {
      long double s;
      if (j <= x_v) s = std::sqrt(2 * j / a);
      else if (j < n - x_v) s = j / v + t_v / 2;
      else s = total - std::sqrt(2 * (n - j) / a);
      t[j] = s * kF;
    }
  } else {
    const long double peak = std::sqrt(n / a);  // time to the middle
    for (uint32_t j = 1; j <= n; ++j) {
      const long double s = 2 * j <= n ? std::sqrt(2 * j / a) : 2 * peak - std::sqrt(2 * (n - j) / a);
      t[j] = s * kF;
    }
  }
  return t;
}

}  // namespace

TEST_CASE("a 10 000-step move at 100 us per step takes 1.000 s") {
  std::ostringstream out;
  std::unique_ptr<SimBoard> holder;
  SimBoard& board = quiet_board({}, out, holder);
  const std::string move = frame({3, 1, 16, 10000, 100});
  board.send(move);
  board.run_for(2 * 48000000);
  const Trace trace = read_trace(out.str());
  const std::vector<Ticks>& steps = trace.steps.at(3);
  REQUIRE(steps.size() == 10000);
  const Ticks start = trace.rx.at(line_of(move));
  const Ticks took = steps.back() - start;
  std::printf("10 000 steps at 100 us: command to last step %llu ticks = %.6f s (first to last %llu ticks)\n",
              static_cast<unsigned long long>(took), static_cast<double>(took) / 48e6,
              static_cast<unsigned long long>(steps.back() - steps.front()));
  std::printf("summary: | step timing, 10 000 steps at 100 us | %.6f s, command to last step | 1.000000 s ideal | "
              "%.6f | within a tick |\n",
              static_cast<double>(took) / 48e6, static_cast<double>(took) / 48e6);
  CHECK(took >= 48000000 - 1);
  CHECK(took <= 48000000 + 1);
}

TEST_CASE("three motors at three rates keep their own schedules") {
  std::ostringstream out;
  std::unique_ptr<SimBoard> holder;
  SimBoard& board = quiet_board({}, out, holder);
  const uint32_t delays[3] = {100, 130, 170};
  std::string moves;
  for (uint32_t m = 1; m <= 3; ++m) moves += frame({m, m == 2 ? 2u : 1u, 16, 2000, delays[m - 1]});
  board.send(moves);
  board.run_for(48000000);
  const Trace trace = read_trace(out.str());
  std::istringstream lines(moves);
  long double worst = 0;
  for (uint32_t m = 1; m <= 3; ++m) {
    std::string line;
    std::getline(lines, line);
    const Ticks start = trace.rx.at(line);
    const std::vector<Ticks>& steps = trace.steps.at(static_cast<int>(m));
    REQUIRE(steps.size() == 2000);
    for (std::size_t j = 1; j <= steps.size(); ++j) {
      const long double ideal = start + static_cast<long double>(j) * delays[m - 1] * 48;
      worst = std::max(worst, std::fabs(static_cast<long double>(steps[j - 1]) - ideal));
    }
  }
  std::printf("three motors at 100/130/170 us: worst step error %.3Lf ticks over 6000 steps\n", worst);
  std::printf("summary: | step timing, 3 motors at 100/130/170 us | worst step error %.3Lf ticks | ideal grid | "
              "%.3Lf of a tick (20.8 ns) | <= 1 tick |\n",
              worst, worst);
  CHECK(worst <= 1.0L);
}

TEST_CASE("ramped moves match the ideal trapezoid within one tick at every step") {
  struct Case {
    uint32_t steps, delay_us, accel;
  };
  long double worst_of_all = 0;
  long double longest_ratio = 0;
  for (const Case c : {Case{3200, 100, 8000}, Case{12000, 100, 20000}, Case{400, 50, 400000}}) {
    std::ostringstream out;
    std::unique_ptr<SimBoard> holder;
    SimConfig config;
    config.accel = {0, 0, c.accel};
    SimBoard& board = quiet_board(config, out, holder);
    const std::string move = frame({3, 1, 16, c.steps, c.delay_us});
    board.send(move);
    board.run_for(5 * 48000000);
    const Trace trace = read_trace(out.str());
    const std::vector<Ticks>& steps = trace.steps.at(3);
    REQUIRE(steps.size() == c.steps);
    const Ticks start = trace.rx.at(line_of(move));
    const std::vector<long double> ideal = ideal_trapezoid(c.steps, c.delay_us * 48, c.accel);
    long double worst = 0;
    for (uint32_t j = 1; j <= c.steps; ++j) {
      worst = std::max(worst, std::fabs(static_cast<long double>(steps[j - 1] - start) - ideal[j]));
    }
    std::printf("ramp %u steps at %u us, %u steps/s^2: worst step error %.3Lf ticks, took %.6Lf s (ideal %.6Lf s)\n",
                c.steps, c.delay_us, c.accel, worst, (steps.back() - start) / kF, ideal[c.steps] / kF);
    CHECK(worst <= 1.0L);
    worst_of_all = std::max(worst_of_all, worst);
    longest_ratio = std::max(longest_ratio, (steps.back() - start) / ideal[c.steps]);
  }
  std::printf("summary: | step timing, 3 trapezoids (400-12 000 steps) | worst step error %.3Lf ticks | ideal "
              "trapezoid | duration %.6Lf of ideal | <= 1 tick |\n",
              worst_of_all, longest_ratio);
}

TEST_CASE("the emergency switch leaves no step edge after it") {
  std::ostringstream out;
  std::unique_ptr<SimBoard> holder;
  SimConfig config;
  config.accel = {0, 20000, 0};
  SimBoard& board = quiet_board(config, out, holder);
  board.send(frame({1, 1, 16, 0, 50}) + frame({2, 2, 16, 0, 100}) + frame({3, 1, 256, 0, 100}));
  board.run_until(250 * 48000 + 7);  // an instant between edges of no particular motor
  board.set_emergency(true);
  board.run_for(48000000);
  const Trace trace = read_trace(out.str());
  std::size_t before = 0, after = 0;
  for (const auto& [motor, steps] : trace.steps) {
    for (const Ticks t : steps) (t > trace.emergency ? after : before) += 1;
  }
  std::printf("emergency at %llu ticks: %zu step edges before, %zu after\n",
              static_cast<unsigned long long>(trace.emergency), before, after);
  std::printf("summary: | emergency stop, 3 motors running | %zu step edges after the switch | %zu before | "
              "halted in the switch interrupt | 0 after |\n",
              after, before);
  // 250 ms at 20 000 (its first step 100 µs after the frame, kPickupTicks: 4 999 steps), ramping
  // to 10 000 (625 steps), and 10 000 steps/s (2 500): 8 124 steps.
  REQUIRE(trace.steps.size() == 3);
  CHECK(before == 8124);
  // The rule allows the one edge in flight; the simulated interrupt halts within the event.
  CHECK(after == 0);
}
