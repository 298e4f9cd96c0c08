// The machine profile and quantities with units: conversions exact to the step, every mistake
// found with its place in one run, the example profiles valid.
#include "hmc/profile.h"

#include <cstdlib>

#include <catch2/catch.hpp>

#include "hmc/units.h"

namespace hmc {
namespace {

Profile parse_ok(const std::string& text) {
  Result<Profile, ProfileError> p = parse_profile(text, "t.toml");
  INFO((p ? std::string() : p.error().text()));
  REQUIRE(p);
  return *p;
}

ProfileError parse_bad(const std::string& text) {
  Result<Profile, ProfileError> p = parse_profile(text, "t.toml");
  REQUIRE_FALSE(p);
  return p.error();
}

const std::string kSlider = R"(
[axis.slide]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
limits = ["0mm", "310mm"]
)";

TEST_CASE("quantities: numbers, units, speeds and accelerations") {
  Result<Quantity> q = parse_quantity("250mm");
  REQUIRE(q);
  CHECK(q->value == 250);
  CHECK(q->unit == Unit::kMm);
  CHECK(q->dimension == Dimension::kPosition);
  q = parse_quantity("-90deg");
  REQUIRE(q);
  CHECK(q->value == -90);
  CHECK(q->unit == Unit::kDeg);
  q = parse_quantity("20 mm/s");
  REQUIRE(q);
  CHECK(q->dimension == Dimension::kSpeed);
  for (const char* text : {"100mm/s2", "100mm/s^2", "100mm/s\xC2\xB2"}) {
    q = parse_quantity(text);
    REQUIRE(q);
    CHECK(q->dimension == Dimension::kAcceleration);
  }
  q = parse_quantity("3200steps");
  REQUIRE(q);
  CHECK(q->unit == Unit::kSteps);
  q = parse_quantity("+0.5rev");
  REQUIRE(q);
  CHECK(q->value == 0.5);
  CHECK(q->unit == Unit::kRev);

  CHECK_THAT(parse_quantity("250").error().message, Catch::Contains("no unit"));
  CHECK_THAT(parse_quantity("250in").error().message, Catch::Contains("unknown unit 'in'"));
  CHECK_THAT(parse_quantity("mm").error().message, Catch::Contains("not a number"));
  CHECK_THAT(parse_quantity("20mm/h").error().message, Catch::Contains("'/h' after its unit"));
}

TEST_CASE("a belt-driven slider: 80 steps per mm, exact conversions both ways") {
  const Profile p = parse_ok(kSlider);
  REQUIRE(p.axes.size() == 1);
  const Axis& slide = p.axes[0];
  CHECK(slide.mm_per_rev == 40);
  CHECK(slide.steps_per_unit() == 80);
  CHECK(slide.units_words() == "mm, rev or steps");
  Result<StepCount> s = slide.to_steps(*parse_quantity("250mm"), Dimension::kPosition);
  REQUIRE(s);
  CHECK(s->steps == 20000);
  CHECK_FALSE(s->rounded());
  s = slide.to_steps(*parse_quantity("0.5rev"), Dimension::kPosition);
  REQUIRE(s);
  CHECK(s->steps == 1600);
  s = slide.to_steps(*parse_quantity("20mm/s"), Dimension::kSpeed);
  REQUIRE(s);
  CHECK(s->steps == 1600);
  // The board counts 1/256 full step: 250 mm = 6.25 turns = 1250 full steps.
  const StepCount board = slide.to_board_position(250);
  CHECK(board.steps == 1250 * 256);
  CHECK(slide.from_board_position(1250 * 256) == 250);
  CHECK(slide.from_board_rate(1600, 16) == 20);
  CHECK(slide.from_board_rate(200, 2) == 20);  // the rate at another microstep
  CHECK(p.find("slide") == &p.axes[0]);
  CHECK(p.find("1") == &p.axes[0]);
  CHECK(p.find("2") == nullptr);
}

TEST_CASE("a value between steps is rounded to the nearest and says so; absolute targets never drift") {
  const Profile p = parse_ok(R"(
[axis.pan]
motor = 1
gear_ratio = 3
rotary = true
)");
  const Axis& pan = p.axes[0];
  Result<StepCount> s = pan.to_steps(*parse_quantity("-90deg"), Dimension::kPosition);
  REQUIRE(s);
  CHECK(s->steps == -2400);
  CHECK_FALSE(s->rounded());
  s = pan.to_steps(*parse_quantity("1deg"), Dimension::kPosition);
  REQUIRE(s);
  CHECK(s->steps == 27);  // 26.67
  CHECK(s->rounded());
  // 1000 moves of 1 degree, each target converted from the absolute angle: the position after
  // them is the exact 26666.67 steps rounded once, not 1000 roundings of 26.67.
  int64_t position = 0;
  for (int i = 1; i <= 1000; ++i) position = pan.to_board_position(i * 1.0).steps;
  CHECK(position == 26667 * 16);
}

TEST_CASE("a unit the axis does not have is refused, naming the axis's units") {
  const Profile p = parse_ok(kSlider);
  Result<StepCount> s = p.axes[0].to_steps(*parse_quantity("90deg"), Dimension::kPosition);
  REQUIRE_FALSE(s);
  CHECK_THAT(s.error().message, Catch::Contains("axis 'slide' is linear: it takes mm, rev or steps, not deg"));
  s = p.axes[0].to_steps(*parse_quantity("20mm/s"), Dimension::kPosition);
  REQUIRE_FALSE(s);
  CHECK_THAT(s.error().message, Catch::Contains("a speed"));
}

TEST_CASE("inverted axes count the other way on the board") {
  const Profile p = parse_ok(R"(
[axis.y]
motor = 2
screw_lead = 8
invert = true
)");
  const Axis& y = p.axes[0];
  CHECK(y.steps_per_unit() == 400);
  CHECK(y.to_board_position(10).steps == -4000 * 16);
  CHECK(y.from_board_position(-4000 * 16) == 10);
}

TEST_CASE("every semantic mistake is reported with its line and column, in one run") {
  const ProfileError e = parse_bad(R"(baud = "fast"
colour = 3

[axis.slide]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
spead = "20mm/s"
limits = ["300mm", "0mm"]

[axis.pan]
motor = 1
rotary = true
limits = ["0mm", "90deg"]
microstep = 12

[axis.lift]
motor = 3
screw_lead = "2mm"
[axis.lift.homing]
end = "forward"
)");
  CHECK_FALSE(e.syntax);
  const std::string text = e.text();
  INFO(text);
  CHECK_THAT(text, Catch::Contains("t.toml:1:8: baud must be a whole number, not a string"));
  CHECK_THAT(text, Catch::Contains("t.toml:2:1: unknown key 'colour' at the top"));
  CHECK_THAT(text, Catch::Contains("t.toml:8:1: unknown key 'spead' in axis 'slide'"));
  CHECK_THAT(text, Catch::Contains("t.toml:9:10: axis 'slide' limits are the wrong way round"));
  CHECK_THAT(text, Catch::Contains("t.toml:14:11: axis 'pan' limits low: axis 'pan' is rotary: it takes deg, rev or steps, not mm"));
  CHECK_THAT(text, Catch::Contains("t.toml:15:13: axis 'pan' microstep must be 1, 2, 4"));
  CHECK_THAT(text, Catch::Contains("t.toml:12:9: motor 1 is named twice: by axis 'slide' (line 5) and by axis 'pan'"));
  CHECK_THAT(text, Catch::Contains("axis 'lift': motor 3 has no limit switches, so it cannot home"));
  CHECK(e.mistakes.size() == 8);
  CHECK_THAT(text, Catch::StartsWith("t.toml:1:8:"));  // in the file's order
}

TEST_CASE("drives: exactly one, a belt needs both its numbers") {
  std::string text = parse_bad("[axis.a]\nmotor = 1\n").text();
  CHECK_THAT(text, Catch::Contains("t.toml:1:7: axis 'a' has no drive"));
  text = parse_bad("[axis.a]\nmotor = 1\nrotary = true\nscrew_lead = 8\n").text();
  CHECK_THAT(text, Catch::Contains("has more than one drive"));
  text = parse_bad("[axis.a]\nmotor = 1\npulley_teeth = 20\n").text();
  CHECK_THAT(text, Catch::Contains("t.toml:3:16: axis 'a' needs both pulley_teeth and belt_pitch"));
  text = parse_bad("[axis.a]\nmotor = 1\nscrew_lead = \"8deg\"\n").text();
  CHECK_THAT(text, Catch::Contains("t.toml:3:14: axis 'a' screw_lead is a length: give it in mm, not deg"));
  text = parse_bad("[axis.a]\nscrew_lead = 8\n").text();
  CHECK_THAT(text, Catch::Contains("axis 'a' has no motor"));
}

TEST_CASE("a TOML syntax error is reported alone, with its place") {
  const ProfileError e = parse_bad("baud = 115200\n[axis.a]\nmotor = = 1\ncolour = 3\n");
  CHECK(e.syntax);
  REQUIRE(e.mistakes.size() == 1);
  CHECK_THAT(e.text(), Catch::StartsWith("t.toml:3:"));
  CHECK_THAT(e.text(), Catch::Contains("TOML syntax"));
  // toml++ refuses a key given twice.
  CHECK(parse_bad("baud = 1200\nbaud = 2400\n").syntax);
}

TEST_CASE("an unreadable file is one clear mistake") {
  Result<Profile, ProfileError> p = load_profile("/nonexistent/hmc.toml");
  REQUIRE_FALSE(p);
  CHECK(p.error().unreadable);
  CHECK_THAT(p.error().text(), Catch::Contains("/nonexistent/hmc.toml: cannot read"));
}

TEST_CASE("the default path follows XDG_CONFIG_HOME, then HOME") {
  setenv("XDG_CONFIG_HOME", "/x/config", 1);
  CHECK(*default_profile_path() == "/x/config/hmc/config.toml");
  unsetenv("XDG_CONFIG_HOME");
  setenv("HOME", "/home/u", 1);
  CHECK(*default_profile_path() == "/home/u/.config/hmc/config.toml");
}

TEST_CASE("the example profiles are valid") {
  for (const char* name : {"camera-slider.toml", "pan-tilt-head.toml", "gantry.toml"}) {
    Result<Profile, ProfileError> p = load_profile(std::string(HMC_EXAMPLES_DIR) + "/" + name);
    INFO(name << ": " << (p ? std::string() : p.error().text()));
    CHECK(p);
  }
  const Profile slider = *load_profile(std::string(HMC_EXAMPLES_DIR) + "/camera-slider.toml");
  REQUIRE(slider.find("slide") != nullptr);
  CHECK(slider.find("slide")->to_board_position(250).steps == 1250 * 256);
  CHECK(*slider.find("slide")->speed == 50);
  CHECK(slider.find("slide")->homing->seek_speed == 20.0);
}

}  // namespace
}  // namespace hmc
