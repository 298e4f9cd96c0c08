// Tests of sim://, the simulated board as a transport: URL options, replies in fast and real
// time, the journal that keeps the board "powered" between commands, and its exclusive use.
#include "hmc/sim_transport.h"

#include <stdlib.h>

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/line_splitter.h"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

// A fresh state directory for one test, named by HMC_SIM_STATE while it lives.
class StateDir {
 public:
  StateDir() {
    std::string pattern = (fs::temp_directory_path() / "hmc-sim-test-XXXXXX").string();
    REQUIRE(mkdtemp(pattern.data()) != nullptr);
    path_ = pattern;
    setenv("HMC_SIM_STATE", path_.c_str(), 1);
  }
  ~StateDir() {
    unsetenv("HMC_SIM_STATE");
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  StateDir(const StateDir&) = delete;
  StateDir& operator=(const StateDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::unique_ptr<hmc::Transport> open(const std::string& url, uint32_t baud = hmc::kDefaultBaud) {
  hmc::PortOptions options;
  options.baud = baud;
  auto port = hmc::open_sim_port(url, options);
  INFO(url);
  if (!port) FAIL(port.error().message);
  return std::move(port.value());
}

std::string frame(const hmc::Command& command) {
  auto encoded = hmc::encode(command);
  REQUIRE(encoded.ok());
  return encoded.value() + "\n";
}

void send(hmc::Transport& port, const hmc::Command& command) { REQUIRE(port.write(frame(command)).ok()); }

// Reads lines until one satisfies `done`, for at most `reads` reads of `timeout` each.
template <typename Done>
std::optional<std::string> read_until(hmc::Transport& port, Done done, int reads = 20,
                                      std::chrono::milliseconds timeout = 1000ms) {
  hmc::LineSplitter lines;
  for (int i = 0; i < reads; ++i) {
    auto bytes = port.read(timeout);
    REQUIRE(bytes.ok());
    lines.feed(*bytes);
    while (auto line = lines.next()) {
      if (done(line->text)) return line->text;
    }
  }
  return std::nullopt;
}

std::optional<std::string> read_frame(hmc::Transport& port, const std::string& name) {
  return read_until(port, [&](const std::string& line) { return line.find("#" + name + "#") != std::string::npos; });
}

// Motor 1 forward 1600 microsteps at 1/16 step: 25 600 units of 1/256 step.
const hmc::StepperMove kMove{1, hmc::proto::kActionForward, 16, 1600, 100};
constexpr int64_t kMoveUnits = 1600 * 16;

// Where the firmware says motor 1 is (STA 1).
hmc::MotorStatus motor_status(hmc::Transport& port) {
  send(port, hmc::StatusQuery{1});
  const auto line = read_frame(port, "STA");
  REQUIRE(line);
  auto decoded = hmc::decode_board_frame(*line);
  REQUIRE(decoded.ok());
  REQUIRE(std::holds_alternative<hmc::MotorStatus>(*decoded));
  return std::get<hmc::MotorStatus>(*decoded);
}

// Moves motor 1 by kMove and waits for its end, which must be at `end`.
void move_and_wait(hmc::Transport& port, int64_t end = kMoveUnits) {
  send(port, kMove);
  const auto line = read_frame(port, "EVD");
  REQUIRE(line);
  auto decoded = hmc::decode_board_frame(*line);
  REQUIRE(decoded.ok());
  REQUIRE(std::holds_alternative<hmc::MotionEnded>(*decoded));
  const auto& ended = std::get<hmc::MotionEnded>(*decoded);
  CHECK(ended.how == hmc::MotionEnd::kCompleted);
  CHECK(ended.position == end);
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("parse_sim_url accepts the board's name and options") {
  auto plain = hmc::parse_sim_url("sim://");
  REQUIRE(plain.ok());
  CHECK(plain->name == "default");
  CHECK_FALSE(plain->fast);
  CHECK_FALSE(plain->seed);
  CHECK_FALSE(plain->legacy);
  CHECK_FALSE(plain->fresh);
  CHECK(plain->keep);
  CHECK(plain->trace.empty());

  auto bench = hmc::parse_sim_url("sim://bench?fast&seed");
  REQUIRE(bench.ok());
  CHECK(bench->name == "bench");
  CHECK(bench->fast);
  CHECK(bench->seed);

  auto all = hmc::parse_sim_url("sim://rig-2.a_b?legacy&fresh&nosave&trace=/tmp/t.jsonl");
  REQUIRE(all.ok());
  CHECK(all->name == "rig-2.a_b");
  CHECK(all->legacy);
  CHECK(all->fresh);
  CHECK_FALSE(all->keep);
  CHECK(all->trace == "/tmp/t.jsonl");

  auto only_options = hmc::parse_sim_url("sim://?fast");
  REQUIRE(only_options.ok());
  CHECK(only_options->name == "default");
  CHECK(only_options->fast);
}

TEST_CASE("parse_sim_url refuses what it does not know, naming it") {
  auto unknown = hmc::parse_sim_url("sim://bench?fast&turbo");
  REQUIRE_FALSE(unknown.ok());
  CHECK_THAT(unknown.error().message, Catch::Contains("'turbo'"));
  CHECK_FALSE(hmc::parse_sim_url("sim://bench?fast=1").ok());
  CHECK_FALSE(hmc::parse_sim_url("sim://bench?trace").ok());
  CHECK_FALSE(hmc::parse_sim_url("sim://../etc").ok());
  CHECK_FALSE(hmc::parse_sim_url("sim://a/b").ok());
  CHECK_FALSE(hmc::parse_sim_url("sim:bench").ok());
  CHECK_FALSE(hmc::parse_sim_url("tcp://127.0.0.1:4000").ok());
}

TEST_CASE("fast: the board answers VER") {
  StateDir state;
  auto port = open("sim://?fast");
  CHECK(port->simulated());
  CHECK(port->description() == "simulated board sim://default (fast)");
  REQUIRE(port->write("STX#1#VER#0#ETX\n").ok());
  const auto line = read_frame(*port, "VER");
  REQUIRE(line);
  CHECK(line->rfind("STX#", 0) == 0);
}

TEST_CASE("the board keeps its state between opens, and a move left running goes on") {
  StateDir state;
  {
    auto port = open("sim://bench?fast");
    move_and_wait(*port);
  }
  {
    auto port = open("sim://bench?fast");
    const hmc::MotorStatus status = motor_status(*port);
    CHECK(status.state == hmc::MotorState::kIdle);
    CHECK(status.position == kMoveUnits);
    CHECK(status.microstep == 16);
    // Closed 20 ms (virtual) into a 160 ms move.
    send(*port, kMove);
    REQUIRE(read_frame(*port, "ACK"));
    REQUIRE(port->read(20ms).ok());
  }
  auto port = open("sim://bench?fast");
  CHECK(motor_status(*port).state == hmc::MotorState::kMoving);
  const auto ended = read_frame(*port, "EVD");
  REQUIRE(ended);
  auto decoded = hmc::decode_board_frame(*ended);
  REQUIRE(decoded.ok());
  CHECK(std::get<hmc::MotionEnded>(*decoded).position == 2 * kMoveUnits);
}

TEST_CASE("real time: the clock goes on from the replayed state") {
  StateDir state;
  {
    auto port = open("sim://bench?fast");
    move_and_wait(*port);
  }
  auto port = open("sim://bench");
  CHECK(port->description() == "simulated board sim://bench (real time)");
  CHECK(motor_status(*port).position == kMoveUnits);
}

TEST_CASE("seed: the board answers nothing") {
  StateDir state;
  auto port = open("sim://?fast&seed");
  CHECK(port->description() == "simulated board sim://default (fast, seed firmware)");
  REQUIRE(port->write("STX#1#VER#0#ETX\n").ok());
  std::string heard;
  for (int i = 0; i < 4; ++i) {
    auto bytes = port->read(50ms);
    REQUIRE(bytes.ok());
    heard += *bytes;
  }
  CHECK(heard.find("VER") == std::string::npos);
  // The seed's board still moves; its state is kept apart from the same name with replies.
  REQUIRE(port->write(frame(kMove)).ok());
  REQUIRE(port->read(500ms).ok());
  port.reset();
  auto replies = open("sim://?fast");
  CHECK(motor_status(*replies).position == 0);
}

TEST_CASE("one program at a time uses a simulated board") {
  StateDir state;
  auto first = open("sim://bench?fast");
  auto second = hmc::open_sim_port("sim://bench?fast", {});
  REQUIRE_FALSE(second.ok());
  CHECK(second.error().message == "sim://bench is in use by another program");
  // Another name is another board.
  CHECK(hmc::open_sim_port("sim://other?fast", {}).ok());
  first.reset();
  CHECK(hmc::open_sim_port("sim://bench?fast", {}).ok());
}

TEST_CASE("?fresh forgets the saved state") {
  StateDir state;
  {
    auto port = open("sim://?fast");
    move_and_wait(*port);
  }
  {
    auto port = open("sim://?fast&fresh");
    CHECK(motor_status(*port).position == 0);
  }
  auto port = open("sim://?fast");
  CHECK(motor_status(*port).position == 0);
}

TEST_CASE("?nosave starts from the saved state and saves nothing") {
  StateDir state;
  {
    auto port = open("sim://?fast");
    move_and_wait(*port);
  }
  {
    auto port = open("sim://?fast&nosave");
    CHECK(port->description() == "simulated board sim://default (fast, not saved)");
    CHECK(motor_status(*port).position == kMoveUnits);
    move_and_wait(*port, 2 * kMoveUnits);
  }
  auto port = open("sim://?fast");
  CHECK(motor_status(*port).position == kMoveUnits);
}

TEST_CASE("a journal that cannot be replayed is set aside and the board starts fresh") {
  StateDir state;
  {
    auto port = open("sim://?fast");
    move_and_wait(*port);
  }
  const fs::path journal = state.path() / "sim-default.journal";
  REQUIRE(fs::exists(journal));
  std::ofstream(journal, std::ios::app) << "w 12 not-hex\n";
  {
    auto port = open("sim://?fast");
    CHECK_THAT(port->description(), Catch::Contains("started fresh"));
    CHECK(motor_status(*port).position == 0);
    move_and_wait(*port);
  }
  CHECK(fs::exists(state.path() / "sim-default.journal.bad"));
  auto port = open("sim://?fast");
  CHECK(port->description() == "simulated board sim://default (fast)");
  CHECK(motor_status(*port).position == kMoveUnits);
}

TEST_CASE("a state directory that cannot be created fails the open, saying so") {
  StateDir state;
  const fs::path file = state.path() / "a-file";
  std::ofstream(file) << "x";
  setenv("HMC_SIM_STATE", (file / "sub").c_str(), 1);
  auto port = hmc::open_sim_port("sim://", {});
  REQUIRE_FALSE(port.ok());
  CHECK_THAT(port.error().message, Catch::Contains("HMC_SIM_STATE"));
}

TEST_CASE("?trace appends this session's events") {
  StateDir state;
  const fs::path trace = state.path() / "trace.jsonl";
  {
    auto port = open("sim://?fast");
    move_and_wait(*port);
  }
  auto port = open("sim://?fast&trace=" + trace.string());
  REQUIRE(port->write("STX#1#VER#0#ETX\n").ok());
  REQUIRE(read_frame(*port, "VER"));
  const std::string text = slurp(trace);  // flushed by the read
  CHECK_THAT(text, Catch::Contains(R"("ev":"rx","line":"STX#1#VER#0#ETX")"));
  CHECK_THAT(text, !Catch::Contains(R"("ev":"step")"));  // the replay is not traced
}

TEST_CASE("real time: a move takes its time on the wall clock") {
  StateDir state;
  auto port = open("sim://");
  // 1600 steps at 1000 µs: 1.6 s.
  const auto start = std::chrono::steady_clock::now();
  send(*port, hmc::StepperMove{1, hmc::proto::kActionForward, 16, 1600, 1000});
  const auto ended = read_until(*port, [](const std::string& line) { return line.find("#EVD#") != std::string::npos; },
                                30, 200ms);
  const auto took = std::chrono::steady_clock::now() - start;
  REQUIRE(ended);
  CHECK(took >= 1500ms);
  CHECK(took < 3000ms);
}

// Not run by default: `sim_transport_test "[replay-cost]"` prints how long reopening takes after
// minutes of virtual time.
TEST_CASE("replay cost", "[.][replay-cost]") {
  StateDir state;
  for (const int minutes : {1, 10}) {
    const std::string url = "sim://cost" + std::to_string(minutes) + "?fast";
    {
      auto port = open(url);
      send(*port, kMove);
      // Returns the boot event, ACK and EVD at once, then runs the whole timeout.
      while (true) {
        auto bytes = port->read(std::chrono::minutes(minutes));
        REQUIRE(bytes.ok());
        if (bytes->empty()) break;
      }
    }
    const auto start = std::chrono::steady_clock::now();
    auto port = open(url);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start);
    std::cout << "journal of " << minutes << " min of virtual time: reopened in " << ms.count() << " ms\n";
  }
}
