// Moves in an axis's units: targets rounded once on the absolute position, speeds as delays,
// accelerations, soft limits judged and sent (an inverted axis's swapped), homing settings.
#include "hmc/axis_moves.h"

#include <catch2/catch.hpp>

namespace hmc {
namespace {

// The camera slider of examples/camera-slider.toml: 80 steps per mm at 1/16.
Axis slider() {
  Result<Profile, ProfileError> p = parse_profile(R"(
[axis.slide]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
limits = ["0mm", "310mm"]
speed = "50mm/s"
accel = "200mm/s2"
[axis.slide.homing]
seek_speed = "20mm/s"
pull_off = "2mm"
)",
                                                  "t.toml");
  REQUIRE(p);
  return p->axes[0];
}

MotorStatus at(int64_t position, bool homed = true) {
  MotorStatus m;
  m.position = position;
  m.microstep = 16;
  m.homed = homed;
  return m;
}

TEST_CASE("a target in mm becomes steps, the profile's speed a delay and its accel steps/s2") {
  UnitMoveRequest r;
  r.to = "250mm";
  Result<UnitMove> move = unit_move(slider(), at(0), r);
  REQUIRE(move);
  REQUIRE(move->move);
  CHECK(move->move->dir == proto::kActionForward);
  CHECK(move->move->steps == 20000);
  CHECK(move->move->microstep == 16);
  CHECK(move->delay_us == 250);  // 50 mm/s = 4000 steps/s
  CHECK(move->accel == 16000);   // 200 mm/s2
  CHECK(move->target_position == 20000 * 16);
  CHECK(move->notes.empty());
}

TEST_CASE("a distance counts from where the motor is; already there is no move") {
  UnitMoveRequest r;
  r.by = "-12.5mm";
  r.speed = "10mm/s";
  Result<UnitMove> move = unit_move(slider(), at(20000 * 16), r);
  REQUIRE(move);
  CHECK(move->move->dir == proto::kActionReverse);
  CHECK(move->move->steps == 1000);
  CHECK(move->delay_us == 1250);
  UnitMoveRequest here;
  here.to = "250mm";
  REQUIRE(unit_move(slider(), at(20000 * 16), here));
  CHECK_FALSE(unit_move(slider(), at(20000 * 16), here)->move);
}

TEST_CASE("rounding is said once, messages name the caller's options") {
  UnitMoveRequest r;
  r.to = "0.01mm";
  Result<UnitMove> move = unit_move(slider(), at(0), r);
  REQUIRE(move);
  REQUIRE(move->notes.size() == 1);
  CHECK(move->notes[0] == "--to 0.01mm on axis 'slide' is 0.8 steps: rounded to 1");
  UnitMoveRequest python;
  python.names = {"to=", "by=", "speed=", "accel="};
  python.to = "90deg";
  Result<UnitMove> wrong = unit_move(slider(), at(0), python);
  REQUIRE_FALSE(wrong);
  CHECK(wrong.error().message.rfind("to=: ", 0) == 0);
  UnitMoveRequest both;
  both.to = "1mm";
  both.by = "1mm";
  CHECK_FALSE(unit_move(slider(), at(0), both));
}

TEST_CASE("acceleration: a bare number is steps/s2, a quantity the axis's, within the board's range") {
  std::vector<std::string> notes;
  CHECK(accel_steps(slider(), "8000", notes).value() == 8000);
  CHECK(accel_steps(slider(), "100mm/s2", notes).value() == 8000);
  CHECK_FALSE(accel_steps(slider(), "99999999999", notes));
  CHECK_FALSE(accel_steps(slider(), "20mm/s", notes));
}

TEST_CASE("soft limits: judged only once homed, sent as LIM in the board's positions") {
  CHECK(beyond_soft_limits(slider(), at(0), 400).has_value());
  CHECK_FALSE(beyond_soft_limits(slider(), at(0), 310).has_value());
  CHECK_FALSE(beyond_soft_limits(slider(), at(0, false), 400).has_value());
  const std::optional<SoftLimits> lim = soft_limits_command(slider());
  REQUIRE(lim);
  CHECK(lim->low_position() == 0);
  CHECK(lim->high_position() == 310 * 80 * 16);
  Axis inverted = slider();
  inverted.invert = true;
  const std::optional<SoftLimits> swapped = soft_limits_command(inverted);
  REQUIRE(swapped);
  CHECK(swapped->low_position() == -310 * 80 * 16);
  CHECK(swapped->high_position() == 0);
  CHECK_FALSE(soft_limits_command(plain_motor_axis(3, 16)));
  CHECK_FALSE(soft_limits_to_send(slider(), at(0, false)));  // not homed: no limits to the board yet
  CHECK(soft_limits_to_send(slider(), at(0)) == soft_limits_command(slider()));
}

TEST_CASE("homing as the profile says, and a motor without a profile axis") {
  const HomingSetup setup = homing_setup(slider(), StepperMove{1, proto::kActionHome, 0, 0, 0});
  CHECK(setup.move.microstep == 16);
  CHECK(setup.move.delay_us == 625);  // 20 mm/s = 1600 steps/s
  REQUIRE(setup.settings.size() == 2);
  CHECK(setup.settings[1].setting == proto::kSettingHomePullOff);
  CHECK(setup.settings[1].value == 160);
  CHECK_FALSE(setup.homed_position);  // the board's re-approach setting decides: kept as it is

  SECTION("a program that owns the board sets what the profile leaves out to none, so it knows where homing ends") {
    const HomingSetup owned = homing_setup(slider(), StepperMove{1, proto::kActionHome, 0, 0, 0}, UnsetHoming::kNone);
    REQUIRE(owned.settings.size() == 3);
    CHECK(owned.settings[2].setting == proto::kSettingHomeLocate);
    CHECK(owned.settings[2].value == 0);
    CHECK(owned.homed_position == 160);  // pulled 2 mm off the reverse switch, not re-approached
    Axis forward = slider();
    forward.homing->end = 1;
    CHECK(homing_setup(forward, StepperMove{1, proto::kActionHome, 0, 0, 0}, UnsetHoming::kNone).homed_position == -160);
    forward.homing->locate_speed = 1;
    CHECK(homing_setup(forward, StepperMove{1, proto::kActionHome, 0, 0, 0}).homed_position == 0);
    Axis bare = slider();
    bare.homing.reset();
    CHECK(homing_setup(bare, StepperMove{1, proto::kActionHome, 0, 0, 0}).settings.empty());
    const HomingSetup none = homing_setup(bare, StepperMove{1, proto::kActionHome, 0, 0, 0}, UnsetHoming::kNone);
    CHECK(none.settings.size() == 3);
    CHECK(none.homed_position == 0);
  }
  const Axis plain = plain_motor_axis(3, 8);
  CHECK(plain.rotary);
  CHECK(plain.steps_per_unit() == Approx(200.0 * 8 / 360));
  CHECK(number_text(26.66666) == "26.667");
  CHECK(number_text(-0.0001) == "0");
}

}  // namespace
}  // namespace hmc
