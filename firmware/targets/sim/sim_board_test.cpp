// Tests of the simulated board itself: virtual time, byte pacing, the virtual DRV8711, axes and
// switches. The board's behaviour (the controller's rules) is tested by the behaviour vectors.
#include "sim_board.h"

#include <catch2/catch.hpp>

#include <sstream>
#include <utility>
#include <vector>

using hmc::sim::Force;
using hmc::sim::kNever;
using hmc::sim::SimBoard;
using hmc::sim::SimConfig;
using hmc::sim::Ticks;

namespace {

constexpr Ticks kMs = 48000;
constexpr Ticks kByte = 4167;  // 10 bits at 115200 baud, rounded up to the tick
// EVB, then EVR: protocol 7, firmware 0.1.0; reset by power-on. 50 bytes, 4.34 ms at 115200.
const std::string kBootEvent = "STX#3#EVB#7#100#107#ETX\nSTX#6#EVR#1#0#0#0#0#1#ETX\n";
constexpr Ticks kBootThrough = 5 * kMs;  // the boot events are through by then

SimConfig quiet_config() {
  SimConfig config;
  config.options.self_test = false;
  return config;
}

}  // namespace

TEST_CASE("boot enables the drivers at the boot microstep and plays the boot tune") {
  SimBoard board(quiet_config());
  board.boot();
  for (uint8_t motor = 1; motor <= 3; ++motor) {
    CHECK(board.driver_enabled(motor));
    CHECK(board.driver_microstep(motor) == hmc::fw::kBootMicrostep);
  }
  board.run_for(500 * kMs);
  REQUIRE(board.tones().size() == 2);
  CHECK(board.tones()[0].hz == hmc::fw::kBootTune[0].hz);
  CHECK(board.tones()[1].t == 120 * kMs);
  CHECK(board.servo_last_pulse(1) == 1472);
}

TEST_CASE("received bytes arrive at the emulated baud rate") {
  SimConfig config = quiet_config();
  config.baud = 115200;
  SimBoard board(config);
  board.boot();
  board.run_until(kBootThrough);
  CHECK(board.take_output() == kBootEvent);
  const std::string frame = "STX#6#LED#1#200#120#100#20#185#ETX\n";
  board.send(frame);
  // 36 bytes at 10 bits each: 3.125 ms. Not answered before the last byte arrives.
  board.run_until(kBootThrough + 3 * kMs);
  CHECK(board.take_output().empty());
  // The reply (16 bytes) is through 1.389 ms after that.
  board.run_until(kBootThrough + 5 * kMs);
  CHECK(board.take_output() == "STX#1#ACK#0#ETX\n");
  CHECK(board.led(1) == std::array<uint8_t, 4>{200, 120, 100, 20});
}

TEST_CASE("sent bytes leave at the emulated baud rate, from when the firmware wrote them") {
  std::ostringstream trace;
  SimConfig config = quiet_config();
  config.baud = 115200;
  SimBoard board(config);
  board.set_trace(&trace);
  board.boot();
  board.run_until(kBootThrough);
  CHECK(board.take_output() == kBootEvent);
  CHECK(board.next_output() == kNever);
  const std::string frame = "STX#6#LED#1#200#120#100#20#185#ETX\n";
  board.send(frame);
  // Answered as the frame's last byte arrives; the trace's "tx" is that write.
  const Ticks written = kBootThrough + frame.size() * kByte;
  board.run_until(written);
  CHECK(trace.str().find("{\"t\":" + std::to_string(written) + ",\"ev\":\"tx\",\"line\":\"STX#1#ACK#0#ETX\"}") !=
        std::string::npos);
  const std::string reply = "STX#1#ACK#0#ETX\n";
  for (size_t i = 0; i < reply.size(); ++i) {
    const Ticks through = written + (i + 1) * kByte;
    CHECK(board.next_output() == through);
    board.run_until(through - 1);
    CHECK(board.take_output().empty());
    CHECK(board.busy());
    board.run_until(through);
    CHECK(board.take_output() == reply.substr(i, 1));
  }
  CHECK(board.next_output() == kNever);
  CHECK_FALSE(board.busy());
}

TEST_CASE("a reply written while the wire is busy leaves after the bytes before it") {
  SimConfig config = quiet_config();
  config.baud = 115200;
  SimBoard board(config);
  board.boot();
  board.run_until(kBootThrough);
  (void)board.take_output();
  // The ACK is written as the frame's end arrives, the NAK of "X" two bytes later, while the
  // ACK is still on the wire.
  const std::string frame = "STX#6#LED#1#200#120#100#20#185#ETX\n";
  board.send(frame + "X\n");
  const Ticks written = kBootThrough + frame.size() * kByte;
  // A run loop that follows next_event() stops at every byte.
  std::vector<std::pair<Ticks, std::string>> got;
  while (board.busy()) {
    board.run_until(board.next_event());
    if (std::string out = board.take_output(); !out.empty()) got.emplace_back(board.now(), std::move(out));
  }
  const std::string replies = "STX#1#ACK#0#ETX\nSTX#4#NAK#3#0#0#3#ETX\n";
  REQUIRE(got.size() == replies.size());
  for (size_t i = 0; i < got.size(); ++i) {
    CHECK(got[i] == std::make_pair(written + (i + 1) * kByte, replies.substr(i, 1)));
  }
}

TEST_CASE("with baud 0 sent bytes are there at once") {
  SimBoard board(quiet_config());
  board.boot();
  CHECK(board.next_output() == 0);
  CHECK(board.take_output() == kBootEvent);
  CHECK(board.next_output() == kNever);
  board.run_until(kMs);
  board.send("STX#6#LED#1#200#120#100#20#185#ETX\n");
  board.run_until(kMs);  // received and answered at this instant
  CHECK(board.next_output() == kMs);
  CHECK(board.take_output() == "STX#1#ACK#0#ETX\n");
  CHECK_FALSE(board.transmitting());
  CHECK_FALSE(board.busy());
}

TEST_CASE("dropped output never arrives, and the wire stays busy until it would have") {
  SimConfig config = quiet_config();
  config.baud = 115200;
  SimBoard board(config);
  board.boot();  // the boot events (50 bytes) are on the wire until 50 byte times
  board.run_until(5 * kByte);
  board.drop_output();
  CHECK(board.next_output() == kNever);
  CHECK_FALSE(board.transmitting());
  // "X" is refused as its end arrives, at 7 byte times: the NAK waits for the boot events' end.
  board.send("X\n");
  board.run_until(7 * kByte);
  CHECK(board.next_output() == 51 * kByte);
  board.run_until(100 * kByte);
  CHECK(board.take_output() == "STX#4#NAK#3#0#0#3#ETX\n");
}

TEST_CASE("take_written gives what the firmware wrote at once, on the wire or not") {
  SimConfig config = quiet_config();
  config.baud = 115200;
  SimBoard board(config);
  board.boot();
  board.run_until(5 * kByte);  // the boot events: 5 of their 50 bytes through
  CHECK(board.take_written() == kBootEvent);
  CHECK_FALSE(board.transmitting());
  CHECK(board.take_output().empty());
  // The wire stays busy for them: a reply written now still leaves after them.
  board.send("X\n");
  board.run_until(7 * kByte);
  CHECK(board.next_output() == 51 * kByte);
}

TEST_CASE("an axis moves by 256/microstep per step and closes its switch at the configured position") {
  SimConfig config = quiet_config();
  config.axes[0] = {true, 1600, 0, 409600};
  SimBoard board(config);
  board.boot();
  // Reverse 200 steps at microstep 16 (16 units each): reaches 0 after 100 steps, where switch
  // end 0 closes and the motor halts.
  board.send("STX#6#STM#1#2#16#200#100#63#ETX\n");
  board.run_for(100 * kMs);
  // The reply, then the switch event and the end of the motion (halted by a limit switch, at
  // -1600: the firmware counts from 0 at power-up).
  CHECK(board.take_output() ==
        kBootEvent + "STX#1#ACK#0#ETX\nSTX#4#EVL#1#0#1#2#ETX\nSTX#5#EVD#1#3#1#1600#69#ETX\n");
  CHECK(board.axis_position(1) == 0);
  CHECK(board.steps(1) == 100);
  CHECK(board.limit_pressed(1, 0));
  CHECK_FALSE(board.busy());
}

TEST_CASE("a forced switch overrides the axis, and the trace records it") {
  std::ostringstream trace;
  SimBoard board(quiet_config());
  board.set_trace(&trace);
  board.boot();
  board.force_limit(2, 1, Force::kPressed);
  CHECK(board.limit_pressed(2, 1));
  board.force_limit(2, 1, Force::kNone);
  CHECK_FALSE(board.limit_pressed(2, 1));
  CHECK(trace.str().find("{\"t\":0,\"ev\":\"switch\",\"motor\":2,\"end\":1,\"pressed\":true}") !=
        std::string::npos);
}
