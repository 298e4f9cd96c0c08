// Behaviour conformance: plays every vector of kind "behaviour" (vectors/behaviour_*.json,
// format in README.md) against the firmware core on the simulated board, in each mode the
// vector names, and checks every expectation at its time.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "sim_board.h"

using json = nlohmann::json;
using hmc::sim::Force;
using hmc::sim::SimBoard;
using hmc::sim::SimConfig;
using hmc::sim::Ticks;

namespace {

SimConfig config_for(const json& vector, const std::string& mode) {
  SimConfig config;
  config.options.self_test = false;
  config.options.legacy = mode != "normal";
  config.options.replies = mode != "seed";
  const json board = vector.value("board", json::object());
  config.options.self_test = board.value("self_test", false);
  config.baud = board.value("baud", 0u);
  if (board.contains("accel")) {
    for (std::size_t i = 0; i < 3; ++i) config.accel[i] = board.at("accel").at(i).get<uint32_t>();
  }
  if (board.contains("axes")) {
    for (const auto& [motor, axis] : board.at("axes").items()) {
      hmc::sim::AxisConfig& a = config.axes.at(std::stoul(motor) - 1);
      a.start = axis.value("start", a.start);
      a.low_switch = axis.value("low", a.low_switch);
      a.high_switch = axis.value("high", a.high_switch);
    }
  }
  return config;
}

Ticks ticks_at(const json& step) {
  return static_cast<Ticks>(std::llround(step.at("at_ms").get<double>() * 48000.0));
}

// What the board sent, split: replies (one per line received) and events (names starting
// with 'E', docs/protocol.md "Telling frames apart").
struct Output {
  std::vector<std::string> replies;
  std::vector<std::string> events;

  void add(const std::string& bytes) {
    std::istringstream in(bytes);
    for (std::string line; std::getline(in, line);) {
      const std::size_t name = line.find('#', line.find('#') + 1) + 1;
      (line.compare(name, 1, "E") == 0 ? events : replies).push_back(line);
    }
  }
};

void apply(SimBoard& board, const json& step) {
  if (step.contains("send")) board.send(step.at("send").get<std::string>() + "\n");
  if (step.contains("send_raw")) board.send(step.at("send_raw").get<std::string>());
  for (const char* key : {"press", "release", "auto"}) {
    if (!step.contains(key)) continue;
    const json& which = step.at(key);
    const Force force = std::string(key) == "press"     ? Force::kPressed
                        : std::string(key) == "release" ? Force::kReleased
                                                        : Force::kNone;
    board.force_limit(which.at(0).get<uint8_t>(), which.at(1).get<uint8_t>(), force);
  }
  if (step.contains("estop")) board.set_emergency(step.at("estop").get<bool>());
  if (step.contains("fault")) {
    board.set_driver_fault(step.at("fault").at(0).get<uint8_t>(), step.at("fault").at(1).get<uint8_t>());
  }
}

// Checks one expectation block; returns the failures, each naming what differed.
std::vector<std::string> check(SimBoard& board, const json& expect, Output& output,
                               const std::string& where) {
  std::vector<std::string> failures;
  const auto fail = [&](const std::string& what, const json& want, const json& got) {
    failures.push_back(where + ": " + what + ": expected " + want.dump() + ", got " + got.dump());
  };
  for (const auto& [key, want] : expect.items()) {
    if (key == "replies" || key == "events") {
      std::vector<std::string>& lines = key == "replies" ? output.replies : output.events;
      const json got = lines;
      if (got != want) fail(key, want, got);
      lines.clear();
      continue;
    }
    if (key == "warnings") {
      std::size_t warnings = 0;
      for (const auto& tone : board.tones()) warnings += tone.hz == hmc::fw::kWarningTune[0].hz;
      if (json(warnings) != want) fail(key, want, warnings);
      continue;
    }
    if (key == "boot_leds") {
      const json got = board.boot_leds();
      if (got != want) fail(key, want, got);
      continue;
    }
    if (key == "tones") {
      json got = json::array();
      for (const auto& tone : board.tones()) got.push_back(tone.hz);
      if (got != want) fail(key, want, got);
      continue;
    }
    for (const auto& [id_text, value] : want.items()) {
      const auto id = static_cast<uint8_t>(std::stoul(id_text));
      const hmc::fw::Controller& c = board.controller();
      json got;
      if (key == "steps") got = board.steps(id);
      else if (key == "position") got = c.position(id);
      else if (key == "axis") got = board.axis_position(id);
      else if (key == "state") got = hmc::sim::state_name(c.state(id));
      else if (key == "running") got = c.scheduler().is_running(id);
      else if (key == "homed") got = c.homed(id);
      else if (key == "microstep") got = board.driver_microstep(id);
      else if (key == "servo") got = board.servo_pulse(id);
      else if (key == "led") got = board.led(id);
      else if (key == "limit") got = {board.limit_pressed(id, 0), board.limit_pressed(id, 1)};
      else {
        failures.push_back(where + ": unknown expectation '" + key + "'");
        break;
      }
      if (got != value) fail(key + "[" + id_text + "]", value, got);
    }
  }
  return failures;
}

struct Tally {
  int vectors = 0;
  int runs = 0;
  int expectations = 0;
};

void run_vector(const json& vector, Tally& tally) {
  const std::string id = vector.at("id").get<std::string>();
  const json modes = vector.value("modes", json{"normal", "legacy"});
  ++tally.vectors;
  for (const json& mode_json : modes) {
    const std::string mode = mode_json.get<std::string>();
    SimBoard board(config_for(vector, mode));
    board.boot();
    Output output;
    ++tally.runs;
    for (const json& step : vector.at("script")) {
      board.run_until(ticks_at(step));
      output.add(board.take_output());
      apply(board, step);
      board.run_until(board.now());  // what arrived at this instant is handled at it
      output.add(board.take_output());
      const std::string key = mode == "normal" ? "expect" : "expect_" + mode;
      const json* expect = step.contains(key) ? &step.at(key) : step.contains("expect") ? &step.at("expect") : nullptr;
      if (expect == nullptr) continue;
      ++tally.expectations;
      const std::string where = id + " [" + mode + "] at " + step.at("at_ms").dump() + " ms";
      for (const std::string& failure : check(board, *expect, output, where)) FAIL_CHECK(failure);
    }
  }
}

}  // namespace

TEST_CASE("behaviour vectors on the simulated board") {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(HMC_VECTORS_DIR)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("behaviour_", 0) == 0 && entry.path().extension() == ".json") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  REQUIRE(!files.empty());
  for (const auto& path : files) {
    std::ifstream in(path);
    const json file = json::parse(in);
    Tally tally;
    for (const json& vector : file.at("vectors")) {
      REQUIRE(vector.at("kind") == "behaviour");
      run_vector(vector, tally);
    }
    std::cout << path.filename().string() << ": " << tally.vectors << " vectors, " << tally.runs
              << " runs, " << tally.expectations << " expectation points\n";
  }
}
