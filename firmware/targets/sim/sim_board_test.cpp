// Tests of the simulated board itself: virtual time, byte pacing, the virtual DRV8711, axes and
// switches. The board's behaviour (the controller's rules) is tested by the behaviour vectors.
#include "sim_board.h"

#include <catch2/catch.hpp>

#include <sstream>

using hmc::sim::Force;
using hmc::sim::SimBoard;
using hmc::sim::SimConfig;
using hmc::sim::Ticks;

namespace {

constexpr Ticks kMs = 48000;

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
  CHECK(board.take_output() == "STX#3#EVB#2#100#102#ETX\n");  // the boot event
  const std::string frame = "STX#6#LED#1#200#120#100#20#185#ETX\n";
  board.send(frame);
  // 36 bytes at 10 bits each: 3.125 ms. Not answered before the last byte arrives.
  board.run_until(3 * kMs);
  CHECK(board.take_output().empty());
  board.run_until(4 * kMs);
  CHECK(board.take_output() == "STX#1#ACK#0#ETX\n");
  CHECK(board.led(1) == std::array<uint8_t, 4>{200, 120, 100, 20});
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
        "STX#3#EVB#2#100#102#ETX\nSTX#1#ACK#0#ETX\nSTX#4#EVL#1#0#1#2#ETX\nSTX#5#EVD#1#3#1#1600#69#ETX\n");
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
