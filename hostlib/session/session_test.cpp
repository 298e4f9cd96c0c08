// Session against the simulated board (sim://, in this process): detection of v2 and seed
// firmware, the model kept from replies and events, checks before sending, refusals explained,
// waits, interruption and a lost link.
#include "hmc/session.h"

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>

#include "hmc/codec.h"
#include "hmc/sim_transport.h"

namespace {

using hmc::Firmware;
using hmc::Millis;
using hmc::MotorState;
using hmc::Session;
using hmc::SessionError;
using hmc::StepperMove;
using hmc::proto::Reason;

constexpr uint32_t kFwd = hmc::proto::kActionForward;
constexpr uint32_t kRev = hmc::proto::kActionReverse;
constexpr uint32_t kHome = hmc::proto::kActionHome;

// Every test gets its own board state directory.
struct StateDir {
  std::filesystem::path path;
  StateDir() {
    path = std::filesystem::temp_directory_path() /
           ("hmc-session-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path);
    ::setenv("HMC_SIM_STATE", path.c_str(), 1);
  }
  ~StateDir() { std::filesystem::remove_all(path); }
  static inline int counter = 0;
};

std::unique_ptr<hmc::Transport> sim(const std::string& url) {
  auto port = hmc::open_sim_port(url, {});
  REQUIRE(port.ok());
  return std::move(port.value());
}

// Counts the lines the host sends.
struct Recorder {
  std::vector<std::string> sent;
  hmc::SessionOptions options() {
    hmc::SessionOptions o;
    o.on_send = [this](std::string_view line) { sent.emplace_back(line); };
    return o;
  }
};

std::unique_ptr<Session> open(const std::string& url, hmc::SessionOptions options = {}) {
  auto session = Session::open(sim(url), options);
  if (!session) FAIL(session.error().message);
  return std::move(session.value());
}

// A transport that fails every read after `good_reads` of them, as an unplugged port does.
class FailingTransport : public hmc::Transport {
 public:
  FailingTransport(std::unique_ptr<hmc::Transport> inner, int good_reads)
      : inner_(std::move(inner)), good_reads_(good_reads) {}
  hmc::Status write(std::string_view bytes) override {
    writes.emplace_back(bytes);
    return inner_->write(bytes);
  }
  hmc::Result<std::string> read(Millis timeout) override {
    if (reads_++ >= good_reads_) return hmc::Error{"lost the connection to the test port (unplugged?)"};
    return inner_->read(timeout);
  }
  std::string description() const override { return "failing test port"; }
  std::vector<std::string> writes;

 private:
  std::unique_ptr<hmc::Transport> inner_;
  int good_reads_;
  int reads_ = 0;
};

// A port opened while the board was sending: the first read brings the end of a line whose
// start was never received, then the board as it is.
class MidLineTransport : public hmc::Transport {
 public:
  explicit MidLineTransport(std::unique_ptr<hmc::Transport> inner) : inner_(std::move(inner)) {}
  hmc::Status write(std::string_view bytes) override { return inner_->write(bytes); }
  hmc::Result<std::string> read(Millis timeout) override {
    if (!cut_sent_) {
      cut_sent_ = true;
      return std::string("#0#0#0#1#ETX\n");
    }
    return inner_->read(timeout);
  }
  std::string description() const override { return "port opened mid-line"; }

 private:
  std::unique_ptr<hmc::Transport> inner_;
  bool cut_sent_ = false;
};

// A board whose firmware predates protocol 4, made from the simulated board: its VER and EVB
// say `protocol` (2 or 3), it sends no EVR, and it refuses the STA units its protocol lacks
// (proto::status_unit_max: 2 answers 1-6, 3 answers 1-7) as out of range, as such a board does.
class OlderBoardTransport : public hmc::Transport {
 public:
  OlderBoardTransport(std::unique_ptr<hmc::Transport> inner, uint32_t protocol)
      : inner_(std::move(inner)), protocol_(protocol) {}
  hmc::Status write(std::string_view bytes) override {
    writes.emplace_back(bytes);
    std::string line(bytes);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    if (auto sent = hmc::decode(line, hmc::proto::ChecksumMode::kSum); sent) {
      if (const auto* query = std::get_if<hmc::StatusQuery>(&sent->command);
          query && query->unit > hmc::proto::status_unit_max(protocol_)) {
        // The unit is token 3, at byte 10 of "STX#2#STA#u#u#ETX".
        pending_ += hmc::encode_board_frame(hmc::Nak{Reason::kOutOfRange, 3, 10}).value() + "\n";
        return hmc::Done{};
      }
      if (const auto* move = std::get_if<hmc::StepperMove>(&sent->command);
          move && move->motor == over_budget_motor) {
        // Over this board's step budget: rate_limit on the delay (token 7, byte 18 for a
        // two-digit microstep).
        pending_ += hmc::encode_board_frame(hmc::Nak{Reason::kRateLimit, 7, 18}).value() + "\n";
        return hmc::Done{};
      }
    }
    return inner_->write(bytes);
  }
  hmc::Result<std::string> read(Millis timeout) override {
    if (pending_.empty()) {
      auto got = inner_->read(timeout);
      if (!got) return got;
      partial_ += got.value();
      for (size_t end; (end = partial_.find('\n')) != std::string::npos; partial_.erase(0, end + 1)) {
        pending_ += rewrite(partial_.substr(0, end));
      }
    }
    return std::exchange(pending_, std::string());
  }
  std::string description() const override { return "protocol " + std::to_string(protocol_) + " test board"; }
  bool sent_status_query(uint32_t unit) const {
    const std::string prefix = "STX#2#STA#" + std::to_string(unit) + "#";
    return std::any_of(writes.begin(), writes.end(), [&](const std::string& w) { return w.rfind(prefix, 0) == 0; });
  }
  std::vector<std::string> writes;
  uint32_t over_budget_motor = 0;  // its moves are refused as over the budget (0: none)

 private:
  std::string rewrite(const std::string& line) const {
    auto frame = hmc::decode_board_frame(line);
    if (!frame) return line + "\n";
    if (std::holds_alternative<hmc::ResetEvent>(*frame)) return "";
    if (auto* v = std::get_if<hmc::Version>(&*frame)) {
      v->protocol = protocol_;
      if (protocol_ < hmc::proto::feature_spec(hmc::proto::Feature::kStepBudgets).since) v->max_ramping_rate.reset();
    }
    if (auto* b = std::get_if<hmc::Booted>(&*frame)) b->protocol = protocol_;
    return hmc::encode_board_frame(*frame).value() + "\n";
  }
  std::unique_ptr<hmc::Transport> inner_;
  uint32_t protocol_;
  std::string partial_, pending_;
};

}  // namespace

TEST_CASE("the reset cause comes with the board's state; a board predating it is told to reflash") {
  {
    StateDir dir;
    auto s = open("sim://?fast");
    CHECK(s->supports(hmc::proto::Feature::kResetCause));
    CHECK(s->supports(hmc::proto::Feature::kLinkWatchdog));
    REQUIRE(s->model().last_reset.has_value());
    CHECK(s->model().last_reset->cause == hmc::proto::ResetCause::kPowerOn);
    REQUIRE(s->model().watchdog.has_value());  // STA 7 was read too
    auto reply = s->execute(hmc::StatusQuery{hmc::proto::kUnitReset});
    REQUIRE(reply.ok());
    REQUIRE(std::holds_alternative<hmc::ResetStatus>(reply.value()));
    CHECK(hmc::describe(reply.value()) == "last reset: power-on");
    auto watchdog = s->execute(hmc::StatusQuery{hmc::proto::kUnitWatchdog});
    REQUIRE(watchdog.ok());
    CHECK(std::holds_alternative<hmc::WatchdogStatus>(watchdog.value()));
  }
  for (const uint32_t protocol : {2u, 3u}) {
    DYNAMIC_SECTION("protocol " << protocol) {
      StateDir dir;
      auto raw = new OlderBoardTransport(sim("sim://?fast"), protocol);
      auto opened = Session::open(std::unique_ptr<hmc::Transport>(raw), {});
      REQUIRE(opened.ok());  // no decode error, no NAK: the host never asked what it lacks
      auto& s = opened.value();
      CHECK(s->version()->protocol == protocol);
      CHECK_FALSE(s->supports(hmc::proto::Feature::kResetCause));
      CHECK(s->supports(hmc::proto::Feature::kLinkWatchdog) == (protocol >= 3));
      CHECK_FALSE(s->model().last_reset.has_value());
      CHECK(s->model().watchdog.has_value() == (protocol >= 3));
      CHECK(raw->sent_status_query(hmc::proto::kUnitLastBase));
      CHECK(raw->sent_status_query(hmc::proto::kUnitWatchdog) == (protocol >= 3));
      CHECK_FALSE(raw->sent_status_query(hmc::proto::kUnitReset));
      const size_t sent = raw->writes.size();
      auto reply = s->execute(hmc::StatusQuery{hmc::proto::kUnitReset});
      REQUIRE_FALSE(reply.ok());
      CHECK(reply.error().kind == SessionError::Kind::kTooOld);
      CHECK(reply.error().message ==
            "the board's firmware is too old for this: reflash (the reset cause and fault record (EVR, STA 8) needs "
            "protocol 4; the board speaks protocol " +
                std::to_string(protocol) + ")");
      if (protocol == 2) {
        auto watchdog = s->execute(hmc::StatusQuery{hmc::proto::kUnitWatchdog});
        REQUIRE_FALSE(watchdog.ok());
        CHECK(watchdog.error().kind == SessionError::Kind::kTooOld);
        CHECK(watchdog.error().message ==
              "the board's firmware is too old for this: reflash (the link watchdog (WDG, STA 7) needs protocol 3; "
              "the board speaks protocol 2)");
      } else {
        auto watchdog = s->execute(hmc::StatusQuery{hmc::proto::kUnitWatchdog});
        REQUIRE(watchdog.ok());
        CHECK(std::holds_alternative<hmc::WatchdogStatus>(watchdog.value()));
      }
      // Sent as a raw line, the board's own refusal: out of range, as the board of that protocol says.
      auto raw_reply = s->send_line("STX#2#STA#8#8#ETX");
      REQUIRE_FALSE(raw_reply.ok());
      CHECK(raw_reply.error().kind == SessionError::Kind::kNak);
      CHECK(raw_reply.error().reason == Reason::kOutOfRange);
      CHECK(raw->writes.size() == sent + (protocol == 2 ? 1 : 2));
    }
  }
}

TEST_CASE("both step budgets from a protocol-7 board; a protocol-6 board's VER of 8 values is no decode error") {
  {
    StateDir dir;
    auto s = open("sim://?fast");
    REQUIRE(s->supports(hmc::proto::Feature::kStepBudgets));
    auto budgets = s->step_budgets();
    REQUIRE(budgets.ok());
    CHECK(budgets.value() == hmc::StepBudgets{hmc::proto::kMaxStepRate, hmc::proto::kMaxRampingStepRate});
    CHECK(s->step_budgets_in_force() == budgets.value());
  }
  StateDir dir;
  auto raw = new OlderBoardTransport(sim("sim://?fast"), 6);
  auto opened = Session::open(std::unique_ptr<hmc::Transport>(raw), {});
  REQUIRE(opened.ok());
  auto& s = opened.value();
  REQUIRE(s->version().has_value());
  CHECK(s->version()->protocol == 6);
  CHECK_FALSE(s->version()->max_ramping_rate.has_value());
  CHECK(s->supports(hmc::proto::Feature::kSetPosition));
  CHECK_FALSE(s->supports(hmc::proto::Feature::kStepBudgets));
  auto budgets = s->step_budgets();
  REQUIRE_FALSE(budgets.ok());
  CHECK(budgets.error().kind == SessionError::Kind::kTooOld);
  CHECK(budgets.error().message ==
        "the board's firmware is too old for this: reflash (VER's ramping step budget (max_ramping_rate) needs "
        "protocol 7; the board speaks protocol 6)");
  // Moves are checked against VER's max_rate and the ramping budget of every protocol-6 firmware.
  CHECK(s->step_budgets_in_force() == hmc::StepBudgets{hmc::proto::kMaxStepRate, 40000});
  // The board's own VER line, 8 values, read as a reply.
  auto ver = s->send_line("STX#1#VER#0#ETX");
  REQUIRE(ver.ok());
  REQUIRE(std::holds_alternative<hmc::Version>(ver.value()));
  CHECK_FALSE(std::get<hmc::Version>(ver.value()).max_ramping_rate.has_value());
}

TEST_CASE("the end of a line begun before the port was opened is passed over, not taken for a broken link") {
  auto session = Session::open(std::make_unique<MidLineTransport>(sim("sim://midline?fast&fresh&nosave")), {});
  REQUIRE(session);
  CHECK(session.value()->firmware() == hmc::Firmware::kV2);
}

TEST_CASE("a v2 board is detected and its state read") {
  StateDir dir;
  auto s = open("sim://?fast");
  CHECK(s->firmware() == Firmware::kV2);
  REQUIRE(s->version().has_value());
  CHECK(s->version()->protocol == hmc::proto::kProtocolVersion);
  CHECK(s->model().reported);
  CHECK(s->model().motor(1).state == MotorState::kIdle);
  CHECK(s->model().motor(1).microstep == 16);
  CHECK(s->model().board.servo1_us == 1472);  // centred at boot
  CHECK(s->description().find("protocol " + std::to_string(hmc::proto::kProtocolVersion)) != std::string::npos);
}

TEST_CASE("a move is waited for and its end position comes from the board") {
  StateDir dir;
  auto s = open("sim://?fast");
  REQUIRE(s->execute(StepperMove{1, kFwd, 16, 1600, 100}).ok());
  CHECK(s->model().motor(1).state == MotorState::kMoving);
  REQUIRE(s->wait_until_idle({1}).ok());
  CHECK(s->model().motor(1).state == MotorState::kIdle);
  CHECK(s->model().motor(1).position == 1600 * 16);
  // Reverse at 1/4: 400 steps of 64 units.
  REQUIRE(s->execute(StepperMove{1, kRev, 4, 400, 100}).ok());
  REQUIRE(s->wait_until_idle({1}).ok());
  CHECK(s->model().motor(1).position == 0);
  CHECK(s->model().motor(1).microstep == 4);
}

TEST_CASE("the host refuses what the board would refuse, sends nothing, and says why") {
  StateDir dir;
  Recorder rec;
  auto s = open("sim://?fast", rec.options());
  REQUIRE(s->execute(StepperMove{2, kFwd, 16, 0, 200}).ok());  // runs until stopped
  const size_t sent = rec.sent.size();
  auto home = s->execute(StepperMove{1, kHome, 0, 0, 0});
  REQUIRE_FALSE(home.ok());
  CHECK(home.error().kind == SessionError::Kind::kRefused);
  CHECK(home.error().reason == Reason::kMotorsRunning);
  CHECK(home.error().message.find("motor 2 moves") != std::string::npos);
  CHECK(rec.sent.size() == sent);

  auto bad = s->execute(StepperMove{1, kFwd, 3, 100, 100});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().kind == SessionError::Kind::kInvalid);
  CHECK(bad.error().message.find("microstep") != std::string::npos);
  REQUIRE(s->stop_all().ok());
  CHECK_FALSE(s->model().any_moving());
}

TEST_CASE("a move toward a pressed switch is refused from the model") {
  StateDir dir;
  auto s = open("sim://?fast");
  // Motor 1 starts mid-travel, 204 800 units above its reverse switch: run into it.
  REQUIRE(s->execute(StepperMove{1, kRev, 1, 2000, 50}).ok());
  REQUIRE(s->wait_until_idle({1}).ok());
  CHECK(s->model().motor(1).switches == 1u);
  CHECK(s->model().board.limit_pressed(1, 0));
  auto again = s->execute(StepperMove{1, kRev, 1, 10, 100});
  REQUIRE_FALSE(again.ok());
  CHECK(again.error().kind == SessionError::Kind::kRefused);
  CHECK(again.error().reason == Reason::kLimitPressed);
  CHECK(again.error().message.find("reverse end is pressed") != std::string::npos);
  CHECK(s->execute(StepperMove{1, kFwd, 1, 10, 100}).ok());  // away from it is fine
}

TEST_CASE("an older board's refusal of a move over its step budget comes back with the sum and the budget") {
  // A protocol-6 board ramps at most 40 000 steps/s in all (this firmware's 150 000 cannot be
  // exceeded by three motors at their max_rate): motor 3 at the spec's 20 us (50 000) at
  // constant rate fits its 150 000; motor 1 ramping beside it does not fit the 40 000, and the
  // board's refusal comes back with the sum and the budget.
  StateDir dir;
  Recorder rec;
  auto raw = new OlderBoardTransport(sim("sim://?fast"), 6);
  raw->over_budget_motor = 1;  // as that board refuses motor 1's move below
  auto opened = Session::open(std::unique_ptr<hmc::Transport>(raw), rec.options());
  REQUIRE(opened.ok());
  auto& s = opened.value();
  REQUIRE(s->execute(StepperMove{3, kFwd, 8, 0, 20}).ok());
  REQUIRE(s->execute(hmc::SetSetting{1, hmc::proto::kSettingAccel, 8000}).ok());
  auto over = s->execute(StepperMove{1, kFwd, 16, 1000, 30});
  REQUIRE_FALSE(over.ok());
  CHECK(over.error().kind == SessionError::Kind::kNak);
  CHECK(over.error().reason == Reason::kRateLimit);
  CHECK(over.error().message.find("motor 1 would step at 33334 steps/s") != std::string::npos);
  CHECK(over.error().message.find("motor 3 at 50000 now") != std::string::npos);
  CHECK(over.error().message.find("83334 steps/s or more together, above its budget while any moving motor "
                                  "ramps, 40000 steps/s (150000 at constant rate)") != std::string::npos);
  REQUIRE(s->stop_all().ok());
}

TEST_CASE("a line the board refuses comes back explained") {
  StateDir dir;
  auto s = open("sim://?fast");
  auto reply = s->send_line("STX#6#STM#3#1#1#11#1000#238#ETX");
  REQUIRE_FALSE(reply.ok());
  CHECK(reply.error().kind == SessionError::Kind::kNak);
  CHECK(reply.error().reason == Reason::kChecksumMismatch);
  CHECK(reply.error().message.find("token 8, byte 24") != std::string::npos);
  // The session still counts replies right afterwards.
  CHECK(s->execute(hmc::ServoMove{1, 135}).ok());
  CHECK(s->model().board.servo1_us == hmc::proto::servo_pulse_us(135));
}

TEST_CASE("state survives between sessions on the same simulated board") {
  StateDir dir;
  {
    auto s = open("sim://keep?fast");
    REQUIRE(s->execute(StepperMove{3, kFwd, 8, 800, 100}).ok());
    REQUIRE(s->wait_until_idle({3}).ok());
    REQUIRE(s->execute(hmc::LedColor{2, 1, 2, 3, 4}).ok());
  }
  auto s = open("sim://keep?fast");
  CHECK(s->model().motor(3).position == 800 * 32);
  CHECK(s->model().motor(3).microstep == 8);
  CHECK(s->model().strips[1].b == 3);
}

TEST_CASE("a board in CRC-16 mode is still recognised") {
  StateDir dir;
  {
    auto s = open("sim://crc?fast");
    REQUIRE(s->execute(hmc::ChecksumModeCommand{1}).ok());
    CHECK(s->version()->checksum_mode == hmc::proto::ChecksumMode::kCrc16);
    CHECK(s->execute(hmc::StatusQuery{1}).ok());  // now in CRC-16 both ways
  }
  auto s = open("sim://crc?fast");
  CHECK(s->firmware() == Firmware::kV2);
  CHECK(s->version()->checksum_mode == hmc::proto::ChecksumMode::kCrc16);
  CHECK(s->execute(hmc::ServoMove{2, 10}).ok());
}

TEST_CASE("a silent board is taken for the seed firmware and timed") {
  StateDir dir;
  Recorder rec;
  auto s = open("sim://?seed", rec.options());
  CHECK(s->firmware() == Firmware::kSeed);
  CHECK_FALSE(s->version().has_value());
  CHECK(s->description().find("seed firmware") != std::string::npos);
  // 200 steps at 1 ms: about 0.2 s, during which servo and LED would be ignored by the board.
  const auto start = hmc::Clock::now();
  REQUIRE(s->execute(StepperMove{1, kFwd, 16, 200, 1000}).ok());
  auto servo = s->execute(hmc::ServoMove{1, 45});
  REQUIRE_FALSE(servo.ok());
  CHECK(servo.error().reason == Reason::kBusy);
  auto query = s->execute(hmc::StatusQuery{1});
  REQUIRE_FALSE(query.ok());
  CHECK(query.error().message.find("seed firmware does not know it") != std::string::npos);
  REQUIRE(s->wait_until_idle({1}).ok());
  const auto took = std::chrono::duration_cast<Millis>(hmc::Clock::now() - start).count();
  CHECK(took >= 200);
  CHECK(took < 1000);
  CHECK(s->model().motor(1).position == 200 * 16);
  CHECK(s->execute(hmc::ServoMove{1, 45}).ok());
}

TEST_CASE("an interrupted wait stops every motor") {
  StateDir dir;
  hmc::SessionOptions options;
  bool stop = false;
  options.interrupted = [&] { return stop; };
  auto s = open("sim://?fast", options);
  REQUIRE(s->execute(StepperMove{3, kFwd, 16, 0, 100}).ok());
  REQUIRE(s->execute(StepperMove{1, kFwd, 16, 100000, 100}).ok());
  stop = true;
  auto waited = s->wait_until_idle({1});
  REQUIRE_FALSE(waited.ok());
  CHECK(waited.error().kind == SessionError::Kind::kInterrupted);
  CHECK(waited.error().message.find("every motor was sent a stop") != std::string::npos);
  CHECK_FALSE(s->model().any_moving());
  stop = false;
  REQUIRE(s->refresh().ok());
  CHECK_FALSE(s->model().any_moving());
  CHECK(s->model().motor(1).position > 0);
  CHECK(s->model().motor(1).position < 100000 * 16);
}

TEST_CASE("a link lost during a wait is an error, and stops are attempted") {
  StateDir dir;
  auto failing = std::make_unique<FailingTransport>(sim("sim://?fast"), 40);
  FailingTransport* port = failing.get();
  auto opened = Session::open(std::move(failing), {});
  REQUIRE(opened.ok());
  auto& s = opened.value();
  REQUIRE(s->execute(StepperMove{3, kFwd, 16, 0, 100}).ok());  // motor 3 has no switch to end it
  auto waited = s->wait_until_idle({3});
  REQUIRE_FALSE(waited.ok());
  CHECK(waited.error().kind == SessionError::Kind::kLink);
  CHECK(waited.error().message.find("unplugged") != std::string::npos);
  // The three stops were written even though no reply could be read.
  int stops = 0;
  for (const std::string& w : port->writes) stops += w.find("STM#1#0") != std::string::npos ||
                                                   w.find("STM#2#0") != std::string::npos ||
                                                   w.find("STM#3#0") != std::string::npos;
  CHECK(stops == 3);
}

TEST_CASE("positions read as full steps") {
  CHECK(hmc::steps_text(819200) == "3200");
  CHECK(hmc::steps_text(64) == "0.25");
  CHECK(hmc::steps_text(-1) == "-0.00390625");
  CHECK(hmc::steps_text(0) == "0");
}

TEST_CASE("a stream keeps lines in flight, and stops at a refusal with the count of what ran") {
  StateDir dir;
  Recorder rec;
  auto s = open("sim://stream?fast", rec.options());
  std::vector<hmc::Command> commands;
  for (uint32_t i = 0; i < 60; ++i) commands.push_back(hmc::LedColor{1 + i % 2, i, 2 * i, 3 * i, 0});
  auto all = s->stream(commands);
  REQUIRE(all.ok());
  CHECK(all->sent == 60);
  CHECK(all->accepted == 60);
  CHECK_FALSE(all->refused);
  CHECK(s->model().strips[1].r == 59);

  // Line 31 moves motor 1 into its pressed... first press it: run it into its reverse switch.
  REQUIRE(s->execute(StepperMove{1, kRev, 1, 2000, 50}).ok());
  REQUIRE(s->wait_until_idle({1}).ok());
  commands.clear();
  for (uint32_t i = 0; i < 30; ++i) commands.push_back(hmc::ServoMove{1, 10 + i});
  commands.push_back(StepperMove{1, kRev, 16, 10, 100});  // toward the pressed switch: refused
  for (uint32_t i = 0; i < 30; ++i) commands.push_back(hmc::ServoMove{2, 10 + i});
  const size_t before = rec.sent.size();
  auto stopped = s->stream(commands);
  REQUIRE(stopped.ok());
  REQUIRE(stopped->refused);
  CHECK(*stopped->refused == 30);
  CHECK(stopped->why.find("reverse end is pressed") != std::string::npos);
  CHECK(stopped->accepted == stopped->sent - 1);  // every other line sent was carried out
  CHECK(stopped->sent > 31);                      // lines were in flight behind the refused one
  CHECK(stopped->sent < 61);                      // ... but the stream stopped there
  CHECK(rec.sent.size() - before == stopped->sent);
  // Pipelined: with 22-byte lines and a 128-byte window, several lines wait for their answers.
  CHECK(stopped->sent - 31 >= 3);
}

TEST_CASE("replies to lines nobody waits for any more are never taken for a later line's") {
  StateDir dir;
  hmc::SessionOptions options;
  bool armed = false;
  int polls = 0;
  options.interrupted = [&] { return armed && ++polls == 2; };  // with the stream's lines in flight
  auto s = open("sim://late?fast", options);
  std::vector<hmc::Command> commands;
  for (uint32_t i = 0; i < 60; ++i) commands.push_back(hmc::ServoMove{1 + i % 2, 10 + i});
  armed = true;
  auto streamed = s->stream(commands);
  REQUIRE_FALSE(streamed.ok());
  CHECK(streamed.error().kind == SessionError::Kind::kInterrupted);
  // The stops' answers, and every one after, are their own lines' (a STA gets a status back).
  for (uint32_t unit = 1; unit <= 4; ++unit) {
    auto reply = s->execute(hmc::StatusQuery{unit});
    REQUIRE(reply.ok());
    if (unit <= 3) {
      REQUIRE(std::holds_alternative<hmc::MotorStatus>(*reply));
      CHECK(std::get<hmc::MotorStatus>(*reply).motor == unit);
    } else {
      CHECK(std::holds_alternative<hmc::BoardStatus>(*reply));
    }
  }
}
