// The gamepad's jog rules (gamepad.h) fed with scripted pad states: no pad exists where tests run.
#include <catch2/catch.hpp>

#include "gamepad.h"

namespace hmc::desk {
namespace {

using Kind = StickCommand::Kind;

GamepadState pad(float left_x = 0, float left_y = 0, float right_y = 0, bool b = false) {
  GamepadState s;
  s.present = true;
  s.axes[GamepadState::kLeftX] = left_x;
  s.axes[GamepadState::kLeftY] = left_y;
  s.axes[GamepadState::kRightY] = right_y;
  s.buttons[GamepadState::kB] = b;
  return s;
}

TEST_CASE("a stick inside the dead zone asks for nothing; beyond it, a rate in steps") {
  CHECK(GamepadJog::level_of(0.0f) == 0);
  CHECK(GamepadJog::level_of(0.1f) == 0);
  CHECK(GamepadJog::level_of(-GamepadJog::kDeadZone) == 0);
  CHECK(GamepadJog::level_of(0.2f) == 1);
  CHECK(GamepadJog::level_of(1.0f) == GamepadJog::kLevels);
  CHECK(GamepadJog::level_of(-1.0f) == -GamepadJog::kLevels);
  CHECK(GamepadJog::level_of(1.5f) == GamepadJog::kLevels);  // a pad reading beyond its range
}

TEST_CASE("hold the stick: a run; lean further: a faster one; let go: a stop") {
  GamepadJog jog;
  std::vector<StickCommand> out = jog.update(pad(1.0f), true);
  REQUIRE(out.size() == 1);
  CHECK(out[0].kind == Kind::kRun);
  CHECK(out[0].axis == 0);
  CHECK(out[0].fraction == 1.0);
  CHECK(jog.running());
  CHECK(jog.update(pad(0.99f), true).empty());  // the same level: nothing re-sent
  out = jog.update(pad(0.5f), true);
  REQUIRE(out.size() == 1);
  CHECK(out[0].fraction == Approx(4.0 / 8));  // (0.5 - 0.15) / 0.85 of 8 levels, rounded up
  out = jog.update(pad(0.05f), true);  // back inside the dead zone
  REQUIRE(out.size() == 1);
  CHECK(out[0].kind == Kind::kStop);
  CHECK_FALSE(jog.running());
  CHECK(jog.update(pad(), true).empty());
}

TEST_CASE("up on a stick is the axis's positive direction; the right stick is the third axis") {
  GamepadJog jog;
  std::vector<StickCommand> out = jog.update(pad(0, -1.0f, 1.0f), true);  // left up, right down
  REQUIRE(out.size() == 2);
  CHECK(out[0].axis == 1);
  CHECK(out[0].fraction == 1.0);
  CHECK(out[1].axis == 2);
  CHECK(out[1].fraction == -1.0);
}

TEST_CASE("B stops everything, and a stick still held starts nothing until let go") {
  GamepadJog jog;
  jog.update(pad(1.0f), true);
  std::vector<StickCommand> out = jog.update(pad(1.0f, 0, 0, true), true);
  REQUIRE(out.size() == 1);
  CHECK(out[0].kind == Kind::kStopAll);
  CHECK_FALSE(jog.running());
  CHECK(jog.update(pad(1.0f, 0, 0, true), true).empty());  // B held
  CHECK(jog.update(pad(1.0f), true).empty());              // B let go, the stick still held
  CHECK(jog.update(pad(), true).empty());                  // the stick let go
  out = jog.update(pad(0.6f), true);                       // held again: runs
  REQUIRE(out.size() == 1);
  CHECK(out[0].kind == Kind::kRun);
}

TEST_CASE("focus lost, pad unplugged: every run stops, and does not restart by itself") {
  GamepadJog jog;
  jog.update(pad(1.0f, -1.0f), true);
  std::vector<StickCommand> out = jog.update(pad(1.0f, -1.0f), false);
  REQUIRE(out.size() == 2);
  CHECK(out[0].kind == Kind::kStop);
  CHECK(out[1].kind == Kind::kStop);
  CHECK(jog.update(pad(1.0f, -1.0f), true).empty());  // focus back, sticks still held: nothing
  CHECK(jog.update(pad(), true).empty());
  jog.update(pad(1.0f), true);
  GamepadState gone;  // unplugged: GLFW reads nothing
  out = jog.update(gone, true);
  REQUIRE(out.size() == 1);
  CHECK(out[0].kind == Kind::kStop);
}

TEST_CASE("STOP ALL from elsewhere halts the pad's runs until the stick is let go") {
  GamepadJog jog;
  jog.update(pad(1.0f), true);
  jog.halt();
  CHECK_FALSE(jog.running());
  CHECK(jog.update(pad(1.0f), true).empty());
  CHECK(jog.update(pad(0), true).empty());
  CHECK(jog.update(pad(-1.0f), true).size() == 1);
}

}  // namespace
}  // namespace hmc::desk
