// Motion planning: profiles into stages (constant, staged, trapezoid, S-curve) on both
// firmwares, coordinated moves ending together with the wire times counted, positions and soft
// limits, the board's rate budget, LED fades, repeats, moves that do not wait, and the plots.
#include "hmc/motion_plan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "hmc/codec.h"
#include "hmc/motion_file.h"

namespace {

using namespace hmc::motion;
using hmc::Command;
using hmc::LedColor;
using hmc::SetSetting;
using hmc::StepperMove;
using hmc::StepBudgets;
namespace proto = hmc::proto;

MotorConfig motor(const std::string& name, uint32_t number, uint32_t microstep = 16) {
  MotorConfig c;
  c.name = name;
  c.motor = number;
  c.microstep = microstep;
  return c;
}

Profile constant(double speed) {
  Profile p;
  p.kind = ProfileKind::kConstant;
  p.speed = speed;
  return p;
}
Profile staged(double speed, uint32_t stages, double accel = 0) {
  Profile p;
  p.kind = ProfileKind::kStaged;
  p.speed = speed;
  p.stages = stages;
  p.accel = accel;
  return p;
}
Profile trapezoid(double speed, double accel) {
  Profile p;
  p.kind = ProfileKind::kTrapezoid;
  p.speed = speed;
  p.accel = accel;
  return p;
}
Profile s_curve(double speed, double accel, double jerk) {
  Profile p = trapezoid(speed, accel);
  p.kind = ProfileKind::kSCurve;
  p.jerk = jerk;
  return p;
}

Location at(uint32_t line) { return Location{"test.json", line, 5, "$.steps[" + std::to_string(line) + "]"}; }

Move move(const std::string& name, double distance, Profile profile, bool absolute = false) {
  Move m;
  m.motor = name;
  m.distance = distance;
  m.absolute = absolute;
  m.profile = profile;
  return m;
}

Step step(decltype(Step::action) action, uint32_t line = 1) {
  Step s;
  s.action = std::move(action);
  s.where = at(line);
  return s;
}
Step move_step(Move m, uint32_t line = 1, bool wait = true) { return step(MoveStep{std::move(m), wait}, line); }

MotionFile file(std::vector<Step> steps, std::vector<MotorConfig> motors = {motor("pan", 1), motor("tilt", 2),
                                                                            motor("lift", 3, 4)}) {
  MotionFile f;
  f.path = "test.json";
  f.motors = std::move(motors);
  f.steps = std::move(steps);
  return f;
}

PlanOptions seed() {
  PlanOptions o;
  o.firmware = TargetFirmware::kSeed;
  return o;
}

Plan plan_ok(const MotionFile& f, const PlanOptions& o = {}) {
  auto r = plan_motion(f, o);
  if (!r.ok()) FAIL("plan failed: " << r.error().front().message);
  return r.value();
}

uint64_t total_steps(const std::vector<Stage>& stages) {
  uint64_t n = 0;
  for (const Stage& s : stages) n += s.steps;
  return n;
}

// The ideal trapezoid's duration from rest to rest, computed here independently.
double ideal_trapezoid_s(double steps, double v, double a) {
  if (steps >= v * v / a) return steps / v + v / a;
  return 2 * std::sqrt(steps / a);
}

double wire_s(const Command& c, uint32_t baud = 115200) {
  return static_cast<double>(hmc::encode(c).value().size() + 1) * 10.0 / baud;
}

// Our firmware answers every line; the runner sends the next once the answer is in. A line
// costs its wire time, a pass of the board's main loop (100 µs) and the ACK's wire time
// ("STX#1#ACK#0#ETX" and its line end: 16 bytes).
constexpr double kLoopS = 100e-6;
double ack_s(uint32_t baud = 115200) { return 16 * 10.0 / baud; }

uint32_t accel_set(const Action& a, uint32_t motor_number) {
  for (const Command& c : a.setup) {
    const auto* s = std::get_if<SetSetting>(&c);
    if (s && s->motor == motor_number && s->setting == hmc::proto::kSettingAccel) return s->value;
  }
  return 0xFFFFFFFFu;
}

// ---------------------------------------------------------------------------------------

TEST_CASE("constant: one stage, the exact steps and delay") {
  const Plan p = plan_ok(file({move_step(move("pan", 800, constant(2000))), move_step(move("tilt", -300, constant(3000)))}));
  REQUIRE(p.actions.size() == 2);
  const Action& a = p.actions[0];
  REQUIRE(a.stages.size() == 1);
  REQUIRE(a.stages[0].size() == 1);
  const Stage& s = a.stages[0][0];
  CHECK(s.motor == 1);
  CHECK(s.dir == hmc::proto::kActionForward);
  CHECK(s.microstep == 16);
  CHECK(s.steps == 800);
  CHECK(s.delay_us == 500);
  CHECK(s.end_s - s.start_s == Approx(0.4));
  CHECK(accel_set(a, 1) == 0);  // the board may keep an acceleration set earlier
  const Stage& r = p.actions[1].stages[0][0];
  CHECK(r.dir == hmc::proto::kActionReverse);
  CHECK(r.steps == 300);
  CHECK(r.delay_us == 333);
  CHECK(p.actions[1].start_s == Approx(a.end_s));
  CHECK(p.tracks.size() == 3);
  CHECK(p.tracks[1].velocity.size() >= 4);
  // The seed's firmware gets no SET.
  CHECK(plan_ok(file({move_step(move("pan", 800, constant(2000)))}), seed()).actions[0].setup.empty());
}

TEST_CASE("staged: 2N-1 stages at exactly r_k, summing to the distance, symmetric") {
  for (uint32_t n : {2u, 3u, 5u}) {
    for (double accel : {0.0, 4000.0}) {
      const Plan p = plan_ok(file({move_step(move("pan", 4000, staged(3000, n, accel)))}), seed());
      const std::vector<Stage>& st = p.actions[0].stages[0];
      REQUIRE(st.size() == 2 * n - 1);
      CHECK(total_steps(st) == 4000);
      for (uint32_t k = 1; k <= n; ++k) {
        const auto expected = static_cast<uint32_t>(std::lround(1e6 / (3000.0 * k / n)));
        CHECK(st[k - 1].delay_us == expected);
        CHECK(st[2 * n - 1 - k].delay_us == expected);
        if (k < n) CHECK(st[k - 1].steps == st[2 * n - 1 - k].steps);
      }
      for (uint32_t k = 1; k < n; ++k) {
        const double rk = 3000.0 * k / n, rp = 3000.0 * (k - 1) / n;
        const double want = accel > 0 ? (rk * rk - rp * rp) / (2 * accel) : 4000.0 / (4 * n);
        CHECK(st[k - 1].steps == std::max<long>(1, std::lround(want)));
      }
      CHECK(p.tracks[0].stage_boundaries_s.size() == 2 * n - 1);
    }
  }
  // The seed's own example: 3 rates.
  const Plan p = plan_ok(file({move_step(move("pan", 1200, staged(3000, 3)))}));
  CHECK(p.actions[0].stages[0].size() == 5);
  CHECK(accel_set(p.actions[0], 1) == 0);
}

TEST_CASE("staged: short distances shrink the ramps, then use fewer rates") {
  // Ramps of 2000²/(2·100) = 20000 steps each cannot fit in 21 steps: shrunk in proportion.
  Plan p = plan_ok(file({move_step(move("pan", 21, staged(2000, 2, 100)))}), seed());
  std::vector<Stage> st = p.actions[0].stages[0];
  REQUIRE(st.size() == 3);
  CHECK(total_steps(st) == 21);
  CHECK(st[0].steps == st[2].steps);
  CHECK(st[1].steps >= 1);
  for (const Stage& s : st) CHECK(s.steps >= 1);

  p = plan_ok(file({move_step(move("pan", 7, staged(4000, 4, 1)))}), seed());
  st = p.actions[0].stages[0];
  REQUIRE(st.size() == 7);  // 2·4-1 = 7: one step each
  for (const Stage& s : st) CHECK(s.steps == 1);

  // 3 steps cannot hold 5 stages: the two lowest rates.
  p = plan_ok(file({move_step(move("pan", 3, staged(3000, 3)))}), seed());
  st = p.actions[0].stages[0];
  REQUIRE(st.size() == 3);
  CHECK(total_steps(st) == 3);
  CHECK(st[0].delay_us == 1000);
  CHECK(st[1].delay_us == 500);
  CHECK(st[2].delay_us == 1000);

  p = plan_ok(file({move_step(move("pan", -1, staged(3000, 3)))}), seed());
  REQUIRE(p.actions[0].stages[0].size() == 1);
  CHECK(p.actions[0].stages[0][0].steps == 1);
  CHECK(p.actions[0].stages[0][0].dir == hmc::proto::kActionReverse);
}

TEST_CASE("trapezoid, our firmware: SET accel, one stage, the ideal trapezoid's timeline") {
  for (double distance : {8000.0, 300.0}) {  // trapezoid, then a triangle
    const Plan p = plan_ok(file({move_step(move("pan", distance, trapezoid(2000, 8000)))}));
    const Action& a = p.actions[0];
    REQUIRE(a.setup.size() == 1);
    CHECK(std::get<SetSetting>(a.setup[0]) == SetSetting{1, hmc::proto::kSettingAccel, 8000});
    REQUIRE(a.stages[0].size() == 1);
    const Stage& s = a.stages[0][0];
    CHECK(s.steps == static_cast<uint32_t>(distance));
    // A triangle is sent with its peak as the rate: the same motion, less of the budget.
    const double peak = std::sqrt(8000 * distance);
    CHECK(s.delay_us == (peak < 2000 ? static_cast<uint32_t>(1e6 / peak) : 500u));
    const double want = ideal_trapezoid_s(distance, 2000, 8000);
    CHECK(s.end_s - s.start_s == Approx(want).epsilon(1e-9));
    // The velocity: from 0 at the start to 0 at the end, peak at the top speed or √(a·d).
    const MotorTrack& t = p.tracks[0];
    double top = 0;
    for (const VelocityPoint& v : t.velocity) top = std::max(top, v.velocity);
    CHECK(top == Approx(std::min(2000.0, peak)));
    CHECK(t.velocity.back().velocity == 0);
    CHECK(p.duration_s == Approx(s.end_s));
    CHECK(t.stage_boundaries_s.empty());
    // The motor starts when its lines have arrived: the SET (answered), then the STM.
    CHECK(s.start_s == Approx(wire_s(a.setup[0]) + kLoopS + ack_s() + wire_s(StepperMove{1, 1, 16, s.steps, s.delay_us}) +
                              kLoopS));
  }
}

TEST_CASE("trapezoid, our firmware: what the board cannot ramp becomes stages") {
  // 5000 steps/s at 100 steps/s² ramps for 50 s; the board ramps for at most 22 s.
  const Plan p = plan_ok(file({move_step(move("pan", 400000, trapezoid(5000, 100)))}));
  CHECK(accel_set(p.actions[0], 1) == 0);
  CHECK(p.actions[0].stages[0].size() == 17);
  CHECK(total_steps(p.actions[0].stages[0]) == 400000);
  // ... but a short move that never gets near that speed is the board's to ramp.
  const Plan q = plan_ok(file({move_step(move("pan", 400, trapezoid(5000, 100)))}));
  CHECK(accel_set(q.actions[0], 1) == 100);
  REQUIRE(q.actions[0].stages[0].size() == 1);
  CHECK(q.actions[0].stages[0][0].end_s - q.actions[0].stages[0][0].start_s == Approx(2 * std::sqrt(400.0 / 100)));
}

TEST_CASE("trapezoid, the seed's firmware: sampled into stages that rise then fall") {
  const Plan p = plan_ok(file({move_step(move("pan", 8000, trapezoid(2000, 8000)))}), seed());
  const Action& a = p.actions[0];
  CHECK(a.setup.empty());
  const std::vector<Stage>& st = a.stages[0];
  CHECK(st.size() == 17);  // 8 per ramp and the top
  CHECK(total_steps(st) == 8000);
  size_t top = 0;
  for (size_t i = 1; i < st.size(); ++i) {
    if (st[i].delay_us < st[top].delay_us) top = i;
  }
  for (size_t i = 1; i <= top; ++i) CHECK(st[i].delay_us <= st[i - 1].delay_us);
  for (size_t i = top + 1; i < st.size(); ++i) CHECK(st[i].delay_us >= st[i - 1].delay_us);
  CHECK(st[top].delay_us == 500);
  CHECK(st.front().delay_us > 4 * st[top].delay_us);
  // The staircase steps as long as the ideal trapezoid (each stage at its stretch's mean rate);
  // between stages the host waits out its margin on the seed's timing (session.h).
  double stepping = 0;
  for (const Stage& s : st) stepping += s.steps * s.delay_us / 1e6;
  CHECK(stepping == Approx(ideal_trapezoid_s(8000, 2000, 8000)).epsilon(0.01));
  for (size_t i = 1; i < st.size(); ++i) {
    const double before = st[i - 1].steps * st[i - 1].delay_us / 1e6;
    const double line = wire_s(StepperMove{st[i].motor, st[i].dir, st[i].microstep, st[i].steps, st[i].delay_us});
    CHECK(st[i].start_s - st[i - 1].end_s == Approx(before * 0.02 + 0.030 + line).margin(1e-9));
  }
  CHECK(p.tracks[0].stage_boundaries_s.size() == st.size());
  // A triangle, and a move of a few steps.
  const Plan q = plan_ok(file({move_step(move("pan", 301, trapezoid(2000, 8000))), move_step(move("tilt", 3, trapezoid(2000, 8000)))}), seed());
  CHECK(total_steps(q.actions[0].stages[0]) == 301);
  CHECK(total_steps(q.actions[1].stages[0]) == 3);
}

TEST_CASE("S-curve: exact sums, longer than the trapezoid with the same acceleration") {
  for (const PlanOptions& o : {PlanOptions{}, seed()}) {
    for (double distance : {20000.0, 1500.0, 40.0}) {
      const Plan p = plan_ok(file({move_step(move("pan", distance, s_curve(4000, 8000, 40000)))}), o);
      const std::vector<Stage>& st = p.actions[0].stages[0];
      CHECK(total_steps(st) == static_cast<uint64_t>(distance));
      double s_dur = 0;  // the stepping, without the pauses between stages
      for (const Stage& s : st) s_dur += s.steps * s.delay_us / 1e6;
      CHECK(s_dur > ideal_trapezoid_s(distance, 4000, 8000));
      if (o.firmware == TargetFirmware::kV2) CHECK(accel_set(p.actions[0], 1) == 0);
      if (distance == 20000) {
        CHECK(st.size() == 25);  // 12 per side and the top
        // Reaching the acceleration and the speed: the trapezoid's time plus a / jerk.
        CHECK(s_dur == Approx(20000.0 / 4000 + 4000.0 / 8000 + 8000.0 / 40000).epsilon(0.01));
      }
    }
  }
}

// Every motor of a coordinated move starts when its STM line has arrived (our firmware: after
// the answers to the lines before it) and all end together, each stage starting after the pause
// the runner needs to learn the one before has ended.
void check_together(const Plan& p, size_t action, uint32_t baud = 115200, bool v2 = true) {
  const Action& a = p.actions[action];
  const double loop = v2 ? kLoopS : 0.0, ack = v2 ? ack_s(baud) : 0.0;
  double t = a.start_s;
  for (const Command& c : a.setup) t += wire_s(c, baud) + loop + ack;
  double first_end = -1, min_period = 1e9, max_period = 0;
  std::vector<double> ends;
  for (const std::vector<Stage>& st : a.stages) {
    REQUIRE(!st.empty());
    t += wire_s(StepperMove{st[0].motor, st[0].dir, st[0].microstep, st[0].steps, st[0].delay_us}, baud) + loop;
    CHECK(st[0].start_s == Approx(t).margin(1e-9));
    t += ack;
    // Recompute the end from the stages alone.
    double end = st[0].start_s;
    const uint32_t accel = accel_set(a, st[0].motor);
    for (size_t i = 0; i < st.size(); ++i) {
      const Stage& s = st[i];
      if (i > 0) {
        const double line = wire_s(StepperMove{s.motor, s.dir, s.microstep, s.steps, s.delay_us}, baud);
        const double pause = s.start_s - st[i - 1].end_s;
        if (v2) {
          // The end event (at most 31 bytes) and the line, two main-loop passes.
          CHECK(pause >= line + 2 * loop);
          CHECK(pause <= line + 2 * loop + 31 * 10.0 / baud);
        } else {
          CHECK(pause == Approx(st[i - 1].steps * st[i - 1].delay_us / 1e6 * 0.02 + 0.030 + line).margin(1e-9));
        }
        end += pause;
      }
      if (accel != 0 && accel != 0xFFFFFFFFu) {
        end += ideal_trapezoid_s(s.steps, 1e6 / s.delay_us, accel);
      } else {
        end += s.steps * s.delay_us / 1e6;
      }
      min_period = std::min(min_period, s.delay_us / 1e6);
      max_period = std::max(max_period, s.delay_us / 1e6);
    }
    CHECK(st.back().end_s == Approx(end).margin(1e-9));
    ends.push_back(end);
    if (first_end < 0) first_end = end;
  }
  // With the seed, within one step period of the slowest motor (motion_plan.cpp, coordinate()).
  for (double e : ends) CHECK(std::fabs(e - first_end) <= (v2 ? min_period : max_period));
  CHECK(a.end_s == Approx(*std::max_element(ends.begin(), ends.end())));
}

TEST_CASE("coordinated: 2 and 3 motors end within one step period, wire times counted") {
  SECTION("two constant rates") {
    const Plan p = plan_ok(file({step(TogetherStep{{move("pan", 8000, constant(4000)), move("tilt", 1234, constant(4000))}})}));
    check_together(p, 0);
    // tilt is slowed: about 1234 steps over pan's 2 s.
    CHECK(p.actions[0].stages[1].front().delay_us > 1500);
  }
  SECTION("three motors, three profiles, our firmware") {
    const Plan p = plan_ok(file({step(TogetherStep{{move("pan", 6400, trapezoid(3200, 16000)),
                                                    move("tilt", -2400, trapezoid(3200, 16000)),
                                                    move("lift", 600, staged(800, 3))}})}));
    check_together(p, 0);
    CHECK(accel_set(p.actions[0], 1) > 0);
    CHECK(accel_set(p.actions[0], 2) > 0);
    CHECK(accel_set(p.actions[0], 2) < 16000);  // tilt's trapezoid slowed to pan's duration
    CHECK(accel_set(p.actions[0], 3) == 0);
  }
  SECTION("three motors, the seed's firmware, a slow line") {
    PlanOptions o = seed();
    o.baud = 9600;
    const Plan p = plan_ok(file({step(TogetherStep{{move("pan", 6400, trapezoid(3200, 16000)),
                                                    move("tilt", 2400, s_curve(3200, 16000, 200000)),
                                                    move("lift", -777, constant(500))}})}),
                           o);
    check_together(p, 0, 9600, false);
  }
}

TEST_CASE("positions: an absolute move needs a known position; soft limits") {
  MotionFile f = file({move_step(move("pan", 1600, constant(2000), true), 7)});
  auto r = plan_motion(f, {});
  REQUIRE(!r.ok());
  REQUIRE(r.error().size() == 1);
  CHECK(r.error()[0].where.line == 7);
  CHECK(r.error()[0].where.path == "$.steps[7]");
  CHECK(r.error()[0].message ==
        "the position of pan is not known here: home it first, or move it by a relative distance");

  // After homing, or with a known start, it is planned from there.
  Plan p = plan_ok(file({step(HomeStep{{"pan"}}), move_step(move("pan", 1600, constant(2000), true))}));
  CHECK(p.actions[0].estimated);
  CHECK(p.actions[0].end_s == Approx(0.5));
  CHECK(p.actions[1].start_s == Approx(0.5));
  CHECK(p.actions[1].stages[0][0].steps == 1600);
  CHECK(p.tracks[0].end_position == 1600);
  CHECK(p.tracks[0].end_known);
  PlanOptions o;
  o.start_position[0] = 2000;
  p = plan_ok(file({move_step(move("pan", 1600, constant(2000), true))}), o);
  CHECK(p.actions[0].stages[0][0].dir == hmc::proto::kActionReverse);
  CHECK(p.actions[0].stages[0][0].steps == 400);
  CHECK(p.tracks[0].start_position == 2000);
  CHECK(p.tracks[1].start_known == false);

  // Soft limits, declared on the motor.
  std::vector<MotorConfig> motors = {motor("pan", 1)};
  motors[0].min_position = -100;
  motors[0].max_position = 4000;
  r = plan_motion(file({step(HomeStep{{"pan"}}), move_step(move("pan", 3000, constant(2000)), 3),
                        move_step(move("pan", 1500, constant(2000)), 4), move_step(move("pan", -200, constant(2000), true), 5)},
                       motors),
                  {});
  REQUIRE(!r.ok());
  REQUIRE(r.error().size() == 2);
  CHECK(r.error()[0].where.line == 4);
  CHECK(r.error()[0].message.find("4500") != std::string::npos);
  CHECK(r.error()[1].where.line == 5);
}

TEST_CASE("the board's rate budget") {
  const std::vector<MotorConfig> three = {motor("pan", 1), motor("tilt", 2), motor("lift", 3)};
  // Motors started one after the other without waiting, each running 1 s (steps = rate).
  const auto running = [&](std::vector<std::pair<double, bool>> rates) {
    const char* names[] = {"pan", "tilt", "lift"};
    std::vector<Step> steps;
    for (size_t i = 0; i < rates.size(); ++i) {
      const auto [rate, ramps] = rates[i];
      steps.push_back(move_step(move(names[i], rate, ramps ? trapezoid(rate, 400000) : constant(rate)),
                                static_cast<uint32_t>(i + 1), i + 1 == rates.size()));
    }
    return file(steps, three);
  };
  // This firmware (protocol_facts.h: 150 000 steps/s, ramping or not): every motor at the spec's
  // fastest, 20 us a step (50 000 steps/s each, the most a motor may go), fits, ramping too.
  static_assert(proto::kMaxStepRate == 150000 && proto::kMaxRampingStepRate == 150000, "");
  CHECK(plan_motion(running({{50000, false}, {50000, false}, {50000, false}}), {}).ok());
  CHECK(plan_motion(running({{50000, true}, {50000, true}, {50000, true}}), {}).ok());

  // A board of the firmware before (VER: 100 000, 80 000 while ramping): two motors at 20 us fit,
  // a third does not; 40 000 + 40 000 at constant rate and a third motor ramping to 1 000: 81 000
  // is within the constant-rate budget but not within the ramping one; 40 000 + 25 000 + 1 000 is.
  PlanOptions before;
  before.budgets = StepBudgets{100000, 80000};
  CHECK(plan_motion(running({{50000, false}, {50000, false}}), before).ok());
  auto r = plan_motion(running({{50000, false}, {50000, false}, {50000, false}}), before);
  REQUIRE(!r.ok());
  CHECK(r.error()[0].message.find("100000") != std::string::npos);
  r = plan_motion(running({{40000, false}, {40000, false}, {1000, true}}), before);
  REQUIRE(!r.ok());
  CHECK(r.error()[0].message.find("80000") != std::string::npos);
  CHECK(plan_motion(running({{40000, false}, {25000, false}, {1000, true}}), before).ok());

  // An older board still (VER: 75 000, 40 000 while ramping) is held to its own.
  PlanOptions older;
  older.budgets = StepBudgets{75000, 40000};
  // One motor ramping on the board at 45 000: above the 40 000 allowed while ramping.
  r = plan_motion(file({move_step(move("pan", 60000, trapezoid(45000, 400000)), 2)}), older);
  REQUIRE(!r.ok());
  CHECK(r.error()[0].message.find("40000") != std::string::npos);
  // ... which the seed's staircase at constant rates may do.
  PlanOptions seed_board = seed();
  seed_board.budgets = older.budgets;
  CHECK(plan_motion(file({move_step(move("pan", 60000, trapezoid(45000, 400000)))}), seed_board).ok());
  // A motor still running from a move that did not wait counts too.
  r = plan_motion(file({move_step(move("pan", 30000, constant(30000)), 1, false),
                        move_step(move("tilt", 30000, constant(30000)), 2, false),
                        move_step(move("lift", 30000, constant(30000)), 3)},
                       three),
                  older);
  REQUIRE(!r.ok());
  CHECK(r.error()[0].where.line >= 2);  // all three start together: the check names a later one
  CHECK(r.error()[0].message.find("75000") != std::string::npos);
  // Faster than one motor may go.
  r = plan_motion(file({move_step(move("pan", 3000, constant(60000)), 3)}), {});
  REQUIRE(!r.ok());
  for (const auto& e : r.error()) WARN(e.where.line << ": " << e.message);
  CHECK(r.error()[0].where.line == 3);
  // 25 000 + 25 000 at once fits that board.
  CHECK(plan_motion(file({move_step(move("pan", 3000, constant(25000)), 1, false),
                          move_step(move("tilt", 3000, constant(25000)), 2)}),
                    older)
            .ok());
}

TEST_CASE("LED fades: one frame every 50 ms, the first the starting colour, the last the target") {
  const Plan p = plan_ok(file({step(LedStep{1, Colour{200, 100, 0, 0}, std::nullopt, 0}),
                               step(LedStep{1, Colour{0, 0, 255, 40}, std::nullopt, 1000}),
                               step(LedStep{2, Colour{10, 0, 0, 0}, Colour{0, 0, 0, 100}, 120}),
                               step(LedStep{2, Colour{0, 0, 0, 0}, std::nullopt, 30})}));
  REQUIRE(p.actions.size() == 4);
  CHECK(p.actions[0].commands.size() == 1);
  const Action& fade = p.actions[1];
  REQUIRE(fade.commands.size() == 21);
  REQUIRE(fade.commands_at_s.size() == 21);
  CHECK(std::get<LedColor>(fade.commands.front()) == LedColor{1, 200, 100, 0, 0});  // the strip's last colour
  CHECK(std::get<LedColor>(fade.commands.back()) == LedColor{1, 0, 0, 255, 40});
  CHECK(std::get<LedColor>(fade.commands[10]) == LedColor{1, 100, 50, 128, 20});
  for (size_t i = 0; i < 21; ++i) CHECK(fade.commands_at_s[i] - fade.start_s == Approx(0.05 * static_cast<double>(i)));
  CHECK(fade.end_s - fade.start_s == Approx(1.0));
  const Action& from = p.actions[2];
  REQUIRE(from.commands.size() == 4);  // 120 ms: 3 intervals of 40 ms
  CHECK(std::get<LedColor>(from.commands.front()) == LedColor{2, 0, 0, 0, 100});
  CHECK(from.commands_at_s[1] - from.start_s == Approx(0.04));
  CHECK(p.actions[3].commands.size() == 2);  // at least the two ends
  CHECK(std::get<LedColor>(p.actions[3].commands.front()) == LedColor{2, 10, 0, 0, 0});
  CHECK(p.duration_s == Approx(1.15));
}

TEST_CASE("repeats are unrolled and numbered") {
  RepeatStep inner{2, {step(WaitStep{100, {}})}};
  RepeatStep outer{3, {move_step(move("pan", 100, constant(1000))), step(std::move(inner))}};
  Step labelled = step(ServoStep{1, 45});
  labelled.label = "look left";
  const Plan p = plan_ok(file({step(std::move(outer)), labelled}));
  REQUIRE(p.actions.size() == 10);
  for (size_t i = 0; i < p.actions.size(); ++i) CHECK(p.actions[i].index == i + 1);
  CHECK(p.actions[0].kind == ActionKind::kMove);
  CHECK(p.actions[3].kind == ActionKind::kMove);
  CHECK(p.actions[0].description == "move pan +100 steps (constant, 1000 steps/s) (repeat 1 of 3)");
  CHECK(p.actions[5].description == "wait 100 ms (repeat 2 of 3, repeat 2 of 2)");
  CHECK(p.actions[9].description == "look left");
  // Each move starts once its lines are in (SET, then STM, both answered).
  const double lines = p.actions[0].stages[0][0].start_s - p.actions[0].start_s;
  CHECK(p.duration_s == Approx(3 * (0.1 + 0.2 + lines)).margin(0.001));
  CHECK(p.tracks[0].end_position == 300);
  CHECK(!p.tracks[0].end_known);  // relative moves from an unknown start
}

TEST_CASE("a move that does not wait, then wait until_done") {
  const Plan p = plan_ok(file({move_step(move("pan", 2000, constant(2000)), 1, false),  // 1 s
                               step(ServoStep{1, 30}), step(WaitStep{200, {}}),
                               step(WaitStep{0, {"pan"}}), move_step(move("tilt", 100, constant(1000)))}));
  REQUIRE(p.actions.size() == 5);
  const double pan_end = p.actions[0].stages[0][0].end_s;
  CHECK(pan_end == Approx(1.0).margin(0.01));
  CHECK(p.actions[0].end_s == 0);
  CHECK(!p.actions[0].wait_for_motors);
  CHECK(p.actions[1].start_s == 0);  // our firmware moves servos while steppers run
  CHECK(p.actions[2].end_s == Approx(0.2));
  CHECK(p.actions[3].start_s == Approx(0.2));
  CHECK(p.actions[3].end_s == Approx(pan_end));
  CHECK(p.actions[3].motors == std::vector<uint32_t>{1});
  CHECK(p.actions[4].start_s == Approx(pan_end));
  // The seed's firmware refuses a servo while a stepper runs: it waits.
  const Plan q = plan_ok(file({move_step(move("pan", 2000, constant(2000)), 1, false), step(ServoStep{1, 30})}), seed());
  CHECK(q.actions[1].start_s == Approx(q.actions[0].stages[0][0].end_s));
  // A later move of the same motor waits until it rests.
  const Plan r = plan_ok(file({move_step(move("pan", 2000, constant(2000)), 1, false), move_step(move("pan", 10, constant(2000)))}));
  CHECK(r.actions[1].start_s == Approx(r.actions[0].stages[0][0].end_s));
}

TEST_CASE("a stop cuts a motion short, braking at the board's acceleration") {
  const Plan p = plan_ok(file({move_step(move("pan", 20000, trapezoid(2000, 4000)), 1, false),
                               move_step(move("tilt", 20000, constant(2000)), 2, false), step(WaitStep{2000, {}}),
                               step(StopStep{})}));
  const Action& stop = p.actions[3];
  CHECK(stop.commands.size() == 3);
  CHECK(std::get<StepperMove>(stop.commands[0]) == StepperMove{1, hmc::proto::kActionStop, 0, 0, 0});
  CHECK(stop.start_s == Approx(2.0));
  CHECK(stop.end_s == Approx(2.5));  // pan brakes from 2000 steps/s at 4000 steps/s²
  CHECK(p.actions[1].stages[0].back().end_s == Approx(2.0));
  CHECK(!p.tracks[0].end_known);
  CHECK(p.tracks[1].velocity.back().t_s == Approx(2.5));
  CHECK(p.duration_s == Approx(2.5));
}

TEST_CASE("homing motor 3 and unknown names are errors") {
  auto r = plan_motion(file({step(HomeStep{{"lift"}}, 2), move_step(move("nope", 10, constant(100)), 3)}), {});
  REQUIRE(!r.ok());
  REQUIRE(r.error().size() == 2);
  CHECK(r.error()[0].where.line == 2);
  CHECK(r.error()[1].where.line == 3);
}

// Checks that every element opened is closed, in order ("<a ...>" "</a>", "<b/>").
bool balanced(const std::string& svg) {
  std::vector<std::string> open;
  size_t i = 0;
  while ((i = svg.find('<', i)) != std::string::npos) {
    const size_t end = svg.find('>', i);
    if (end == std::string::npos) return false;
    const std::string tag = svg.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return false;
    if (tag[0] == '/') {
      if (open.empty() || open.back() != tag.substr(1)) return false;
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(tag.substr(0, tag.find_first_of(" \n")));
    }
  }
  return open.empty();
}

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
  return n;
}

TEST_CASE("plots: an SVG panel per motor, CSV rows for every point") {
  const Plan p = plan_ok(file({step(HomeStep{{"pan", "tilt"}}),
                               step(TogetherStep{{move("pan", 6400, trapezoid(3200, 16000), true),
                                                  move("tilt", 2400, staged(3200, 3)), move("lift", 600, constant(800))}}),
                               step(LedStep{1, Colour{255, 0, 0, 0}, std::nullopt, 500})}));
  const std::string svg = plot_svg(p, "pan & tilt <demo>");
  CHECK(svg.rfind("<svg", 0) == 0);
  CHECK(balanced(svg));
  CHECK(count(svg, "<polyline") == p.tracks.size());
  CHECK(svg.find("pan &amp; tilt &lt;demo&gt;") != std::string::npos);
  CHECK(svg.find("tilt (motor 2)") != std::string::npos);
  CHECK(svg.find("stroke-dasharray") != std::string::npos);
  CHECK(svg.find("http") == svg.find("http://www.w3.org/2000/svg"));  // no outside resources

  const std::string csv = plot_csv(p);
  size_t points = 0;
  for (const MotorTrack& t : p.tracks) points += t.velocity.size();
  CHECK(count(csv, "\n") == points + 1);
  CHECK(csv.rfind("t_s,motor,name,velocity\n", 0) == 0);
  CHECK(csv.find(",2,tilt,") != std::string::npos);

  const Plan empty = plan_ok(file({}, {}));
  CHECK(balanced(plot_svg(empty, "nothing")));
}

// Found by the motion_file fuzzer (its long run): a `together` step whose slowest move needs a
// delay far beyond what the board can time made fit_ramp() count delays for ever.
TEST_CASE("a coordinated move far slower than the board can time is planned at once") {
  const std::string text = R"({"hmc_motion": 1, "name": "seed", "motors": {"pan": {"motor": 1, "limits": {"min": -100, "max": {"rev": 2}}}, "tilt": {"motor": 2, "microstep": 4, "gear_ratio": 2.5, "speed": {"rpm": 30}, "accel": 8000}, "spin": {"motor": 3, "steps_per_rev": 400, "microstep": 1}}, "steps": [
{"home": ["pan", "tilt"]},
{"together": [{"motor": "pan", "to": 400}, {"motor": "tilt", "by": -1, "speed": 1.5}, {"motor": "spin", "by": 186400000, "accel": 10, "profile": "s-curve"}]},
{"stop": ["pan", "spin"]}
]})";
  const auto parsed = parse_motion_file(text, "slow.json");
  REQUIRE(parsed.ok());
  const auto plan = plan_motion(*parsed, {});  // returns (it used to loop for ever)
  if (!plan.ok()) CHECK(!plan.error().empty());
}

}  // namespace
