// Every example motion file, run on the simulated board, against its plan: the board's trace
// must show exactly the planned step counts, each constant-rate stage at exactly its planned
// delay, coordinated motors finishing within one step period of each other, and every motor
// ending where the plan says.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "hmc/codec.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "hmc/motion_runner.h"
#include "hmc/session.h"
#include "hmc/sim_transport.h"

#ifndef HMC_EXAMPLES_DIR
#error "HMC_EXAMPLES_DIR must be defined by the build"
#endif

namespace {

using namespace hmc;
constexpr uint64_t kTicksPerUs = 48;

struct TraceStep {
  uint64_t t;
  int64_t pos;
};
struct TraceLine {
  uint64_t t;
  std::string line;
};
struct Trace {
  std::map<uint32_t, std::vector<TraceStep>> steps;  // per motor
  std::vector<TraceLine> rx;
};

Trace read_trace(const std::string& path) {
  Trace trace;
  std::ifstream in(path);
  std::string text;
  while (std::getline(in, text)) {
    const nlohmann::json j = nlohmann::json::parse(text);
    const std::string ev = j.at("ev");
    if (ev == "step") trace.steps[j.at("motor").get<uint32_t>()].push_back({j.at("t"), j.at("pos")});
    if (ev == "rx") trace.rx.push_back({j.at("t"), j.at("line")});
  }
  return trace;
}

// A move's STM line as the board received it, with when it arrived.
struct ReceivedMove {
  uint64_t t;
  StepperMove move;
  bool ramped;  // an acceleration was set for the motor when it arrived
};

std::vector<ReceivedMove> received_moves(const Trace& trace) {
  std::vector<ReceivedMove> moves;
  std::map<uint32_t, uint32_t> accel;
  for (const TraceLine& l : trace.rx) {
    auto decoded = decode(l.line);
    REQUIRE(decoded.ok());
    if (const auto* set = std::get_if<SetSetting>(&decoded->command); set && set->setting == proto::kSettingAccel) {
      accel[set->motor] = set->value;
    }
    if (const auto* m = std::get_if<StepperMove>(&decoded->command)) moves.push_back({l.t, *m, accel[m->motor] != 0});
  }
  return moves;
}

motion::Plan run_example(const std::string& name) {
  INFO("example " << name);
  const std::string dir = std::filesystem::temp_directory_path() / ("hmc-examples-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  ::setenv("HMC_SIM_STATE", dir.c_str(), 1);
  const std::string trace_path = dir + "/" + name + ".jsonl";
  std::filesystem::remove(trace_path);

  auto file = motion::load_motion_file(std::string(HMC_EXAMPLES_DIR) + "/" + name);
  REQUIRE(file.ok());
  motion::PlanOptions options;
  for (auto& p : options.start_position) p = 0;  // a board just powered up counts from 0
  auto plan = motion::plan_motion(*file, options);
  REQUIRE(plan.ok());

  {
    auto port = open_sim_port("sim://examples?fast&fresh&nosave&trace=" + trace_path, {});
    REQUIRE(port.ok());
    auto session = Session::open(std::move(port.value()), {});
    REQUIRE(session.ok());
    motion::MotionRunner runner(*session.value(), *plan);
    const motion::RunReport report = runner.run({});
    if (report.error) FAIL(report.error->message);
    CHECK(report.completed == plan->actions.size());
    REQUIRE(session.value()->refresh().ok());
    for (const motion::MotorTrack& t : plan->tracks) {
      INFO("motor " << t.name);
      CHECK(session.value()->model().motor(t.motor).position == t.end_position * 256 / t.microstep);
    }
  }

  const Trace trace = read_trace(trace_path);
  const std::vector<ReceivedMove> moves = received_moves(trace);
  // Step counts and stage rates: the steps between a move's arrival and the next line for the
  // same motor are exactly the move's, at exactly its delay when it does not ramp.
  size_t checked = 0;
  for (size_t i = 0; i < moves.size(); ++i) {
    const ReceivedMove& m = moves[i];
    if (m.move.dir != proto::kActionForward && m.move.dir != proto::kActionReverse) continue;
    uint64_t until = UINT64_MAX;
    for (size_t k = i + 1; k < moves.size(); ++k) {
      if (moves[k].move.motor == m.move.motor) {
        until = moves[k].t;
        break;
      }
    }
    std::vector<uint64_t> times;
    for (const TraceStep& s : trace.steps.at(m.move.motor)) {
      if (s.t > m.t && s.t <= until) times.push_back(s.t);
    }
    INFO("move " << describe(Command{m.move}) << " received at tick " << m.t);
    REQUIRE(times.size() == m.move.steps);
    if (!m.ramped) {
      for (size_t k = 1; k < times.size(); ++k) REQUIRE(times[k] - times[k - 1] == uint64_t{m.move.delay_us} * kTicksPerUs);
    }
    ++checked;
  }
  CHECK(checked > 0);

  // Coordinated moves: the plan's stages are found in the received lines in order; each
  // motor's last step after its last stage's line marks its end, and the ends lie within one
  // step period of each other.
  size_t cursor = 0;
  for (const motion::Action& a : plan->actions) {
    if (a.stages.empty()) continue;
    size_t next_cursor = cursor;
    std::vector<uint64_t> ends;
    uint64_t longest_period = 0;
    for (const std::vector<motion::Stage>& motor_stages : a.stages) {
      if (motor_stages.empty()) continue;  // a move that ends on the step it starts from sends nothing
      size_t at = cursor;
      size_t last_at = 0;
      for (const motion::Stage& stage : motor_stages) {
        const StepperMove expected{stage.motor, stage.dir, stage.microstep, stage.steps, stage.delay_us};
        while (at < moves.size() && !(moves[at].move == expected)) ++at;
        REQUIRE(at < moves.size());
        last_at = at++;
      }
      next_cursor = std::max(next_cursor, last_at + 1);
      const motion::Stage& last = motor_stages.back();
      longest_period = std::max<uint64_t>(longest_period, uint64_t{last.delay_us} * kTicksPerUs);
      uint64_t until = UINT64_MAX;
      for (size_t k = last_at + 1; k < moves.size(); ++k) {
        if (moves[k].move.motor == last.motor) {
          until = moves[k].t;
          break;
        }
      }
      uint64_t end_t = 0;
      for (const TraceStep& s : trace.steps.at(last.motor)) {
        if (s.t > moves[last_at].t && s.t <= until) end_t = s.t;
      }
      ends.push_back(end_t);
    }
    cursor = next_cursor;
    if (ends.size() < 2) continue;
    const auto [lo, hi] = std::minmax_element(ends.begin(), ends.end());
    INFO("coordinated step " << a.index << ": " << a.description);
    CHECK(*hi - *lo <= longest_period);
  }
  return std::move(*plan);
}

}  // namespace

TEST_CASE("pan-tilt scan") { run_example("pan-tilt-scan.json"); }
TEST_CASE("camera slider") { run_example("camera-slider.json"); }
TEST_CASE("home then together") { run_example("home-then-together.json"); }
TEST_CASE("light show") { run_example("light-show.json"); }
// In millimetres through camera-slider.toml (80 steps per mm): the board ends at exactly the
// steps the millimetres come to, counted from exact ends, not from each rounded move.
TEST_CASE("camera slider in millimetres") {
  const motion::Plan plan = run_example("camera-slider-mm.json");
  REQUIRE(plan.tracks.size() == 1);
  CHECK(plan.tracks[0].name == "slide");
  CHECK(plan.tracks[0].end_position == 988);  // 12.3456 mm = 987.648 steps
  int64_t position = 0;
  std::vector<int64_t> ends;
  for (const motion::Action& a : plan.actions) {
    for (const auto& stages : a.stages) {
      for (const motion::Stage& s : stages) position += (s.dir == proto::kActionForward ? 1 : -1) * int64_t{s.steps};
    }
    if (a.kind == motion::ActionKind::kMove) ends.push_back(position);
  }
  REQUIRE(ends.size() == 52);
  CHECK(ends[0] == 20000);       // 250 mm
  CHECK(ends[50] == 20000 - 40); // 50 x 0.8 steps back: 40, not 50
  CHECK(ends[51] == 988);
}
TEST_CASE("stress: short moves") { run_example("stress-short-moves.json"); }
