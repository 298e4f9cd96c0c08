// Unit tests of motion files in a rig's own terms and of checking in one pass (motion_file.h):
// comments and trailing commas, a file naming its machine profile (examples/*.toml) with the
// axes' names, units, directions and limits, roundings that do not add up, and planning's
// mistakes reported with reading's.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hmc/motion_file.h"
#include "hmc/axis_moves.h"
#include "hmc/motion_plan.h"
#include "hmc/motion_runner.h"

#if !defined(HMC_EXAMPLES_DIR) || !defined(HMC_DOCS_DIR)
#error "HMC_EXAMPLES_DIR and HMC_DOCS_DIR must be defined by the build"
#endif

namespace {

using namespace hmc::motion;

// A motion file that sits beside the example profiles, so that "profile" names one of them.
const std::string kBeside = std::string(HMC_EXAMPLES_DIR) + "/test.json";

MotionFile parse_ok(const std::string& text, const std::string& path = kBeside) {
  auto r = parse_motion_file(text, path);
  if (!r) {
    for (const FileError& e : r.error()) UNSCOPED_INFO(e.text());
  }
  REQUIRE(r.ok());
  return std::move(r).value();
}

std::vector<FileError> parse_errors(const std::string& text, const std::string& path = kBeside) {
  auto r = parse_motion_file(text, path);
  REQUIRE_FALSE(r.ok());
  for (const FileError& e : r.error()) UNSCOPED_INFO(e.text());
  return r.error();
}

const Move& move_of(const Step& s) { return std::get<MoveStep>(s.action).move; }

std::string slider(const std::string& steps) {
  return R"({"hmc_motion": 1, "profile": "camera-slider.toml", "steps": [)" + steps + "]}";
}
std::string pan_tilt(const std::string& steps) {
  return R"({"hmc_motion": 1, "profile": "pan-tilt-head.toml", "steps": [)" + steps + "]}";
}

}  // namespace

TEST_CASE("comments are allowed, and a trailing comma is named") {
  const MotionFile f = parse_ok(R"(// a choreography
{
  "hmc_motion": 1, /* the format */
  "motors": {"m": {"motor": 1}},  // one motor
  "steps": [/* nothing yet */ {"wait": {"ms": 1}}]
}
// the end)");
  CHECK(f.steps.size() == 1);

  SECTION("a mistake after a comment of several lines is still at its line") {
    const auto errors = parse_errors("{\"hmc_motion\": 1, /* one\ntwo\nthree */ \"motors\": {\"m\": {\"motor\": 4}},\n"
                                     "\"steps\": [{\"wait\": {\"ms\": 1}}]}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 3);
    CHECK(errors[0].where.path == "$.motors.m.motor");
  }
  SECTION("a comment never closed") {
    const auto errors = parse_errors("{\"hmc_motion\": 1 /* open\n");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 1);
    CHECK(errors[0].where.column == 18);
    CHECK(errors[0].message == "invalid JSON: a comment opened with '/*' is never closed");
  }
  SECTION("a trailing comma in an object, and in a list") {
    auto errors = parse_errors("{\"hmc_motion\": 1,\n \"motors\": {\"m\": {\"motor\": 1},},\n \"steps\": []}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 2);
    CHECK(errors[0].message ==
          "invalid JSON: trailing comma: the ',' at line 2, column 30 is followed by '}'; remove it");
    errors = parse_errors("{\"steps\": [1, 2,\n]}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.steps[2]");
    CHECK(errors[0].message.find("trailing comma: the ',' at line 1, column 16") != std::string::npos);
  }
  SECTION("a lone slash is no comment") {
    const auto errors = parse_errors("{\"hmc_motion\": 1 / 2}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].message.find("trailing comma") == std::string::npos);
  }
}

TEST_CASE("a file names its profile and moves the axes in millimetres") {
  const MotionFile f = parse_ok(slider(R"(
    {"home": "slide"},
    {"move": {"motor": "slide", "to": {"mm": 250}, "speed": {"mm_per_s": 20}, "accel": {"mm_per_s2": 100}}},
    {"move": {"motor": "slide", "by": {"mm": -0.01}}},
    {"move": {"motor": "slide", "to": {"rev": 1}, "profile": "s-curve", "jerk": {"mm_per_s3": 1000}}},
    {"move": {"motor": "slide", "by": 8}})"));
  CHECK(f.profile == std::string(HMC_EXAMPLES_DIR) + "/camera-slider.toml");
  REQUIRE(f.motors.size() == 1);
  const MotorConfig& slide = f.motors[0];
  CHECK(slide.name == "slide");
  CHECK(slide.motor == 1);
  CHECK(slide.microstep == 16);
  CHECK(slide.speed == Approx(4000));   // 50 mm/s at 80 steps per mm
  CHECK(slide.accel == Approx(16000));  // 200 mm/s²
  CHECK(*slide.min_position == Approx(0));
  CHECK(*slide.max_position == Approx(24800));  // 310 mm
  CHECK(move_of(f.steps[1]).distance == 20000);
  CHECK_FALSE(move_of(f.steps[1]).exact);
  CHECK(move_of(f.steps[1]).profile.speed == Approx(1600));
  CHECK(move_of(f.steps[1]).profile.accel == Approx(8000));
  CHECK(move_of(f.steps[2]).distance == -1);
  CHECK(*move_of(f.steps[2]).exact == Approx(-0.8));
  CHECK(move_of(f.steps[3]).distance == 3200);  // a turn of the pulley
  CHECK(move_of(f.steps[3]).profile.jerk == Approx(80000));
  CHECK(move_of(f.steps[4]).distance == 8);  // steps are steps
  // The one value between steps is said, where it is.
  REQUIRE(f.notes.size() == 1);
  CHECK(f.notes[0].where.path == "$.steps[2].move.by.mm");
  CHECK(f.notes[0].text() == kBeside + ":4:46: $.steps[2].move.by.mm: -0.01 mm is -0.8 steps: the move ends at the "
                                       "whole step nearest its exact end, so roundings do not add up");
}

TEST_CASE("an inverted rotary axis counts the other way, and a rounded position is noted") {
  const MotionFile f = parse_ok(pan_tilt(R"({"home": ["pan", "tilt"]},
    {"move": {"motor": "tilt", "to": {"deg": -90}}},
    {"move": {"motor": "pan", "to": {"deg": 1}}})"));
  const MotorConfig* tilt = f.motor("tilt");
  REQUIRE(tilt != nullptr);
  // 200 x 16 x 2 / 360 = 17.78 steps per degree; limits -180..0 degrees, inverted: 0..3200 steps.
  CHECK(*tilt->min_position == Approx(0));
  CHECK(*tilt->max_position == Approx(3200));
  CHECK(move_of(f.steps[1]).distance == 1600);
  REQUIRE(f.notes.size() == 1);
  CHECK(f.notes[0].message == "position 1 deg is 26.6667 steps: rounded to 27");
}

TEST_CASE("roundings do not add up: relative moves count from exact ends") {
  // 300 moves of one degree on pan (26.667 steps each) end at 8000 steps, where rounding each
  // would end at 8100.
  const MotionFile f = parse_ok(pan_tilt(R"({"home": "pan"},
    {"repeat": {"count": 300, "steps": [{"move": {"motor": "pan", "by": {"deg": 1}, "speed": {"deg_per_s": 300}}}]}})"));
  auto plan = plan_motion(f, {});
  REQUIRE(plan.ok());
  REQUIRE(plan->tracks.size() == 2);
  CHECK(plan->tracks[0].name == "pan");
  CHECK(plan->tracks[0].end_position == 8000);
  int64_t longest = 0, shortest = 100;
  for (const Action& a : plan->actions) {
    for (const auto& stages : a.stages) {
      int64_t steps = 0;
      for (const Stage& s : stages) steps += s.steps;
      if (a.kind == ActionKind::kMove) longest = std::max(longest, steps), shortest = std::min(shortest, steps);
    }
  }
  CHECK(longest == 27);
  CHECK(shortest == 26);
}

TEST_CASE("mistakes in the profile's terms") {
  SECTION("a unit the axis does not have") {
    const auto errors = parse_errors(slider(R"({"move": {"motor": "slide", "by": {"deg": 5}}})"));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.steps[0].move.by.deg");
    CHECK(errors[0].expected == "one of steps, mm, rev");
  }
  SECTION("beyond the profile's soft limit") {
    const auto errors = parse_errors(slider(R"({"home": "slide"}, {"move": {"motor": "slide", "to": {"mm": 320}}})"));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].message == "position 320 mm (25600 steps) is above slide's max limit 24800 steps");
  }
  SECTION("millimetres on a motor without a profile") {
    const auto errors = parse_errors(
        R"({"hmc_motion": 1, "motors": {"m": {"motor": 1}}, "steps": [{"move": {"motor": "m", "by": {"mm": 5}}}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].expected == "one of steps, deg, rev");
  }
  SECTION("both a profile and motors") {
    const auto errors = parse_errors(
        R"({"hmc_motion": 1, "profile": "camera-slider.toml", "motors": {"m": {"motor": 1}}, "steps": [{"home": "slide"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.motors");
  }
  SECTION("a profile that cannot be read") {
    const auto errors = parse_errors(R"({"hmc_motion": 1, "profile": "no-such.toml", "steps": [{"home": "x"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.profile");
    CHECK(errors[0].message.rfind("cannot read the profile " + std::string(HMC_EXAMPLES_DIR) + "/no-such.toml", 0) == 0);
  }
  SECTION("a profile with mistakes, from a program's own loader") {
    ReadOptions options;
    options.load_profile = [](const std::string& name, const std::string&) -> hmc::Result<hmc::Profile, std::string> {
      auto p = hmc::parse_profile("[axis.x]\nmotor = 7\nrotary = true\n", name);
      if (p) return std::move(*p);
      return "the profile " + name + " has mistakes";
    };
    auto r = parse_motion_file(R"({"hmc_motion": 1, "profile": "mine", "steps": [{"home": "x"}]})", "f.json", options);
    REQUIRE_FALSE(r.ok());
    REQUIRE(r.error().size() == 1);
    CHECK(r.error()[0].message == "the profile mine has mistakes");
  }
  SECTION("a program's chosen profile, for a file that declares no motors") {
    auto profile = hmc::load_profile(std::string(HMC_EXAMPLES_DIR) + "/camera-slider.toml");
    REQUIRE(profile.ok());
    ReadOptions options;
    options.profile = &*profile;
    auto r = parse_motion_file(R"({"hmc_motion": 1, "steps": [{"move": {"motor": "slide", "by": {"mm": 1}}}]})",
                               "f.json", options);
    REQUIRE(r.ok());
    CHECK(move_of(r->steps[0]).distance == 80);
  }
}

TEST_CASE("one pass: planning's mistakes come with reading's, as far as the broken steps allow") {
  const std::string head = R"({"hmc_motion": 1, "motors": {"m": {"motor": 1, "limits": {"max": 1000}}}, "steps": [)";
  SECTION("a 'to' before homing, a bad servo angle and a 'by' beyond the limit, in one run") {
    const auto errors = parse_errors(head + R"(
      {"move": {"motor": "m", "to": 100}},
      {"servo": {"id": 1, "angle": 200}},
      {"home": "m"},
      {"move": {"motor": "m", "by": 1500}}]})");
    REQUIRE(errors.size() == 3);
    CHECK(errors[0].where.line == 2);
    CHECK(errors[0].message.find("the position of m is not known here") == 0);
    CHECK(errors[1].where.path == "$.steps[1].servo.angle");
    CHECK(errors[2].where.line == 5);
    CHECK(errors[2].message == "m would end at 1500 steps, beyond its soft limit of 1000 steps");
  }
  SECTION("after a broken move the position is not followed, until a 'to' sets it again") {
    const auto errors = parse_errors(head + R"(
      {"home": "m"},
      {"move": {"motor": "m", "by": 500, "sped": 1}},
      {"move": {"motor": "m", "by": 800}},
      {"move": {"motor": "m", "to": 900}},
      {"move": {"motor": "m", "by": 200}}]})");
    REQUIRE(errors.size() == 2);
    CHECK(errors[0].where.path == "$.steps[1].move.sped");
    CHECK(errors[1].where.line == 6);
    CHECK(errors[1].message == "m would end at 1100 steps, beyond its soft limit of 1000 steps");
  }
  SECTION("a sound file's planning mistakes are planning's, as before") {
    auto r = parse_motion_file(head + R"({"move": {"motor": "m", "to": 100}}]})", "f.json");
    REQUIRE(r.ok());
    CHECK_FALSE(plan_motion(*r, {}).ok());
  }
}

hmc::Profile example_profile(const std::string& name) {
  auto p = hmc::load_profile(std::string(HMC_EXAMPLES_DIR) + "/" + name);
  REQUIRE(p.ok());
  return std::move(p).value();
}

TEST_CASE("a program's chosen profile: the axes of a file naming none; a file naming another is refused") {
  const hmc::Profile slider_rig = example_profile("camera-slider.toml");
  const hmc::Profile pan_tilt_rig = example_profile("pan-tilt-head.toml");
  ReadOptions read;
  read.profile = &slider_rig;
  read.profile_chosen_by = "--profile";

  SECTION("a file that names no profile and declares no motors moves the chosen profile's axes") {
    auto f = parse_motion_file(R"({"hmc_motion": 1, "steps": [{"move": {"motor": "slide", "by": {"mm": 10}}}]})",
                               "/nowhere/bare.json", read);
    REQUIRE(f.ok());
    CHECK(f->profile == slider_rig.path);
    CHECK(move_of(f->steps[0]).distance == 800);
  }
  SECTION("a file that declares its motors keeps them") {
    auto f = parse_motion_file(R"({"hmc_motion": 1, "motors": {"m": {"motor": 2}}, "steps": [{"home": "m"}]})",
                               "/nowhere/own.json", read);
    REQUIRE(f.ok());
    CHECK(f->profile.empty());
    CHECK(f->motors[0].name == "m");
  }
  SECTION("the same profile, named by the file, is no mistake") {
    CHECK(parse_motion_file(slider(R"({"home": "slide"})"), kBeside, read).ok());
  }
  SECTION("another profile than the chosen one is a mistake at the file's \"profile\", naming both") {
    read.profile = &pan_tilt_rig;
    const auto r = parse_motion_file(slider(R"({"home": "slide"})"), kBeside, read);
    REQUIRE_FALSE(r.ok());
    REQUIRE(r.error().size() == 1);
    CHECK(r.error()[0].where.path == "$.profile");
    CHECK(r.error()[0].message == "the file was written for the profile " + slider_rig.path + ", not for " +
                                      pan_tilt_rig.path + ", which --profile chooses: give --profile the file's "
                                      "profile, or none");
  }
  SECTION("a profile chosen by default gives way to the file's, with a note") {
    read.profile = &pan_tilt_rig;
    read.profile_chosen_by.clear();
    const auto r = parse_motion_file(slider(R"({"home": "slide"})"), kBeside, read);
    REQUIRE(r.ok());
    CHECK(r->motors[0].name == "slide");
    REQUIRE(r->notes.size() == 1);
    CHECK(r->notes[0].message == "the file's profile " + slider_rig.path + " is used, not the default " + pan_tilt_rig.path);
  }
  SECTION("a copy of the file's profile elsewhere is the same profile") {
    const std::string copy = (std::filesystem::temp_directory_path() / "hmc-camera-slider-copy.toml").string();
    {
      std::ifstream in(slider_rig.path, std::ios::binary);
      std::ofstream out(copy, std::ios::binary | std::ios::trunc);
      out << in.rdbuf();
    }
    hmc::Profile elsewhere = slider_rig;
    elsewhere.path = copy;
    read.profile = &elsewhere;
    CHECK(parse_motion_file(slider(R"({"home": "slide"})"), kBeside, read).ok());
    std::filesystem::remove(copy);
  }
}

TEST_CASE("a profile axis homes as its profile says: settings first, its soft limits after") {
  // A belt axis (40 steps per mm) that seeks its reverse switch at 25 mm/s and pulls off 2 mm,
  // without a slow re-approach: homing leaves it 2 mm off the switch.
  ReadOptions read;
  read.load_profile = [](const std::string&, const std::string&) -> hmc::Result<hmc::Profile, std::string> {
    auto p = hmc::parse_profile(R"([axis.x]
motor = 1
microstep = 8
pulley_teeth = 20
belt_pitch = "2mm"
limits = ["0mm", "300mm"]
[axis.x.homing]
seek_speed = "25mm/s"
pull_off = "2mm"
)",
                                "rig.toml");
    REQUIRE(p.ok());
    return std::move(p).value();
  };
  auto read_file = parse_motion_file(R"({"hmc_motion": 1, "profile": "rig.toml", "steps": [{"home": "x"},
    {"move": {"motor": "x", "to": {"mm": 10}}}]})",
                                     kBeside, read);
  REQUIRE(read_file.ok());
  const MotionFile& f = *read_file;
  const hmc::Axis& x = *f.motor("x")->axis;
  auto plan = plan_motion(f, {});
  REQUIRE(plan.ok());
  const Action& home = plan->actions[0];
  const hmc::HomingSetup setup = hmc::homing_setup(x, hmc::StepperMove{x.motor, hmc::proto::kActionHome, 0, 0, 0},
                                                   hmc::UnsetHoming::kNone);
  REQUIRE(home.setup.size() == setup.settings.size());
  for (size_t i = 0; i < setup.settings.size(); ++i) CHECK(std::get<hmc::SetSetting>(home.setup[i]) == setup.settings[i]);
  REQUIRE(home.commands.size() == 2);
  CHECK(std::get<hmc::StepperMove>(home.commands[0]) == setup.move);
  CHECK(std::get<hmc::SoftLimits>(home.commands[1]) == *hmc::soft_limits_command(x));
  REQUIRE(setup.homed_position == 80);
  REQUIRE(home.homed_at == std::vector<int64_t>{*setup.homed_position});
  // The move to 10 mm counts from where homing left the motor.
  const int64_t ten_mm = std::llround(10 * x.steps_per_unit());
  int64_t moved = 0;
  for (const Stage& s : plan->actions[1].stages[0]) moved += s.steps;
  CHECK(moved == ten_mm - *setup.homed_position);
  CHECK(plan->tracks[0].end_position == ten_mm);

  SECTION("with the seed's firmware, which has no SET, homing settings are a mistake") {
    PlanOptions seed;
    seed.firmware = TargetFirmware::kSeed;
    const auto r = plan_motion(f, seed);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error()[0].message == "the homing settings of axis 'x' (docs/config.md) need SET, which the seed firmware does not know");
  }
}

TEST_CASE("a motor standing between two steps: positions bring it nearest, a resume returns it exactly") {
  // Motor 3 at 0.75 of a step (moved at a finer microstep): the plan counts from 1, and the motor
  // stays 0.25 of a step below every position the plan gives it.
  const MotionFile f = parse_ok(R"({"hmc_motion": 1, "motors": {"m": {"motor": 3, "gear_ratio": 3}}, "steps": [
    {"move": {"motor": "m", "by": {"deg": 1}}},
    {"move": {"motor": "m", "to": {"deg": 2}}}]})");
  PlanOptions options;
  options.start_position[2] = 0.75;
  auto plan = plan_motion(f, options);
  REQUIRE(plan.ok());
  CHECK(plan->tracks[0].start_position == 1);
  CHECK(plan->tracks[0].start_exact == 0.75);
  // by 1 deg (26.667 steps): from 1 to the step nearest 27.667, 28; the motor at 27.75.
  CHECK(plan->actions[0].stages[0][0].steps == 27);
  // to 2 deg (53.333 steps): the motor can stand at 52.75 or 53.75; the nearer is the plan's 54,
  // where rounding the position alone would give 53 (the motor at 52.75).
  CHECK(plan->tracks[0].end_position == 54);
  const auto at2 = planned_positions(*plan, 2);
  REQUIRE(at2[2]);
  CHECK(*at2[2] == 27.75);
  CHECK(*planned_positions(*plan, 3)[2] == 53.75);
}

TEST_CASE("docs/motion-files.md's examples with comments are valid files beside the example profiles") {
  std::ifstream doc(HMC_DOCS_DIR "/motion-files.md");
  REQUIRE(doc);
  std::stringstream text;
  text << doc.rdbuf();
  const std::string md = text.str();
  const std::string fence = "```jsonc\n";
  int checked = 0;
  for (size_t at = md.find(fence); at != std::string::npos; at = md.find(fence, at + 1)) {
    const auto close = md.find("```", at + fence.size());
    REQUIRE(close != std::string::npos);
    const std::string block = md.substr(at + fence.size(), close - at - fence.size());
    INFO(block);
    parse_ok(block);
    ++checked;
  }
  CHECK(checked > 0);
}
