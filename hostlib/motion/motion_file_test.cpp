// Unit tests of motion files (motion_file.h): the documented example, unit conversions, and
// that mistakes are all reported, each at the right line, column and path. Over 600 lines
// because it walks every mistake the format names, one section each, beside the example it
// reads; files in a profile's terms and one-pass checking are motion_file_profile_test.cpp.
#include "hmc/motion_file.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

using namespace hmc::motion;

namespace {

// The example of docs/motion-files.md (the test below checks the doc holds this same text).
const std::string kExample = R"({
  "hmc_motion": 1,
  "name": "pan-tilt scan",
  "motors": {
    "pan":  {"motor": 1, "steps_per_rev": 200, "microstep": 16, "gear_ratio": 1,
             "speed": {"deg_per_s": 90}, "accel": {"deg_per_s2": 360},
             "limits": {"min": {"deg": -10}, "max": {"deg": 350}}},
    "tilt": {"motor": 2, "microstep": 8}
  },
  "steps": [
    {"home": ["pan", "tilt"]},
    {"move": {"motor": "pan", "by": {"deg": 90}, "speed": {"deg_per_s": 45}, "profile": "trapezoid", "accel": {"deg_per_s2": 180}}, "label": "pan right"},
    {"move": {"motor": "tilt", "to": {"steps": 400}, "profile": "staged", "stages": 3, "wait": false}},
    {"together": [{"motor": "pan", "by": {"rev": -0.25}}, {"motor": "tilt", "to": 0, "profile": "s-curve", "accel": 20000, "jerk": {"steps_per_s3": 100000}}]},
    {"servo": {"id": 1, "angle": 135}},
    {"led": {"strip": 1, "colour": "#ff800000"}},
    {"led": {"strip": 2, "colour": [0, 0, 255, 0], "from": "#000000", "fade_ms": 2000}},
    {"wait": {"ms": 500}},
    {"wait": {"until_done": ["tilt"]}},
    {"repeat": {"count": 3, "steps": [{"servo": {"id": 2, "angle": 30}}, {"wait": {"ms": 200}}]}},
    {"stop": "all"}
  ]
}
)";

MotionFile parse_ok(const std::string& text) {
  auto r = parse_motion_file(text, "ok.json");
  if (!r) {
    for (const FileError& e : r.error()) UNSCOPED_INFO(e.text());
  }
  REQUIRE(r.ok());
  return std::move(r).value();
}

std::vector<FileError> parse_errors(const std::string& text) {
  auto r = parse_motion_file(text, "bad.json");
  REQUIRE_FALSE(r.ok());
  for (const FileError& e : r.error()) UNSCOPED_INFO(e.text());
  return r.error();
}

// Motors "m" (motor 1, with the given extra fields) and "n" (motor 2), and the given steps.
std::string with_steps(const std::string& steps, const std::string& motor_fields = "") {
  return R"({"hmc_motion": 1, "motors": {"m": {"motor": 1)" + motor_fields + R"(}, "n": {"motor": 2}}, "steps": [)" +
         steps + "]}";
}

const Move& move_of(const Step& s) { return std::get<MoveStep>(s.action).move; }

}  // namespace

TEST_CASE("the documented example parses into converted values") {
  const MotionFile f = parse_ok(kExample);
  CHECK(f.version == 1);
  CHECK(f.name == "pan-tilt scan");
  CHECK(f.path == "ok.json");

  REQUIRE(f.motors.size() == 2);
  const MotorConfig& pan = f.motors[0];
  CHECK(pan.name == "pan");
  CHECK(pan.motor == 1);
  CHECK(pan.full_steps_per_rev == 200);
  CHECK(pan.microstep == 16);
  CHECK(pan.gear_ratio == 1.0);
  CHECK(pan.steps_per_degree() == Approx(3200.0 / 360));
  CHECK(pan.speed == Approx(800));    // 90 deg/s at 3200 steps/rev
  CHECK(pan.accel == Approx(3200));   // 360 deg/s²
  REQUIRE(pan.min_position);
  REQUIRE(pan.max_position);
  CHECK(*pan.min_position == Approx(-3200.0 / 36));
  CHECK(*pan.max_position == Approx(3200.0 * 350 / 360));
  CHECK(pan.where.line == 5);
  CHECK(pan.where.column == 13);
  CHECK(pan.where.path == "$.motors.pan");
  const MotorConfig& tilt = f.motors[1];
  CHECK(tilt.motor == 2);
  CHECK(tilt.microstep == 8);
  CHECK(tilt.full_steps_per_rev == 200);
  CHECK(tilt.speed == 1000);
  CHECK(tilt.accel == 0);
  CHECK_FALSE(tilt.min_position);
  CHECK(f.motor("tilt") == &f.motors[1]);
  CHECK(f.motor("nope") == nullptr);

  REQUIRE(f.steps.size() == 11);
  CHECK(std::get<HomeStep>(f.steps[0].action).motors == std::vector<std::string>{"pan", "tilt"});
  CHECK(f.steps[0].where.line == 11);
  CHECK(f.steps[0].where.column == 5);
  CHECK(f.steps[0].where.path == "$.steps[0]");

  const MoveStep& m1 = std::get<MoveStep>(f.steps[1].action);
  CHECK(f.steps[1].label == "pan right");
  CHECK(m1.wait);
  CHECK(m1.move.motor == "pan");
  CHECK_FALSE(m1.move.absolute);
  CHECK(m1.move.distance == 800);  // 90 deg at 200 steps/rev x 16
  CHECK(m1.move.profile.kind == ProfileKind::kTrapezoid);
  CHECK(m1.move.profile.speed == Approx(400));
  CHECK(m1.move.profile.accel == Approx(1600));
  CHECK(m1.move.where.path == "$.steps[1].move");
  CHECK(m1.move.where.line == 12);
  CHECK(m1.move.where.column == 14);

  const MoveStep& m2 = std::get<MoveStep>(f.steps[2].action);
  CHECK_FALSE(m2.wait);
  CHECK(m2.move.absolute);
  CHECK(m2.move.distance == 400);
  CHECK(m2.move.profile.kind == ProfileKind::kStaged);
  CHECK(m2.move.profile.stages == 3);
  CHECK(m2.move.profile.speed == 1000);  // the motor's default
  CHECK(m2.move.profile.accel == 0);

  const TogetherStep& t = std::get<TogetherStep>(f.steps[3].action);
  REQUIRE(t.moves.size() == 2);
  CHECK(t.moves[0].motor == "pan");
  CHECK(t.moves[0].distance == -800);  // a quarter turn back
  CHECK(t.moves[0].profile.kind == ProfileKind::kTrapezoid);  // the motor's accel is above 0
  CHECK(t.moves[0].profile.speed == Approx(800));
  CHECK(t.moves[0].profile.accel == Approx(3200));
  CHECK(t.moves[0].where.path == "$.steps[3].together[0]");
  CHECK(t.moves[1].absolute);
  CHECK(t.moves[1].distance == 0);
  CHECK(t.moves[1].profile.kind == ProfileKind::kSCurve);
  CHECK(t.moves[1].profile.accel == 20000);
  CHECK(t.moves[1].profile.jerk == 100000);

  const ServoStep& sv = std::get<ServoStep>(f.steps[4].action);
  CHECK(sv.servo == 1);
  CHECK(sv.angle == 135);

  const LedStep& l1 = std::get<LedStep>(f.steps[5].action);
  CHECK(l1.strip == 1);
  CHECK((l1.colour.r == 255 && l1.colour.g == 128 && l1.colour.b == 0 && l1.colour.w == 0));
  CHECK_FALSE(l1.from);
  CHECK(l1.fade_ms == 0);
  const LedStep& l2 = std::get<LedStep>(f.steps[6].action);
  CHECK(l2.strip == 2);
  CHECK((l2.colour.r == 0 && l2.colour.g == 0 && l2.colour.b == 255 && l2.colour.w == 0));
  REQUIRE(l2.from);
  CHECK((l2.from->r == 0 && l2.from->g == 0 && l2.from->b == 0 && l2.from->w == 0));
  CHECK(l2.fade_ms == 2000);

  CHECK(std::get<WaitStep>(f.steps[7].action).ms == 500);
  CHECK(std::get<WaitStep>(f.steps[8].action).until_done == std::vector<std::string>{"tilt"});

  const RepeatStep& r = std::get<RepeatStep>(f.steps[9].action);
  CHECK(r.count == 3);
  REQUIRE(r.steps.size() == 2);
  CHECK(std::get<ServoStep>(r.steps[0].action).servo == 2);
  CHECK(std::get<ServoStep>(r.steps[0].action).angle == 30);
  CHECK(r.steps[1].where.path == "$.steps[9].repeat.steps[1]");

  CHECK(std::get<StopStep>(f.steps[10].action).motors.empty());  // "all"
}

TEST_CASE("the s-curve of the example needs an acceleration: without one it is the only error") {
  std::string text = kExample;
  const std::string accel = R"("accel": 20000, )";
  const auto at = text.find(accel);
  REQUIRE(at != std::string::npos);
  text.erase(at, accel.size());
  const auto errors = parse_errors(text);
  REQUIRE(errors.size() == 1);
  CHECK(errors[0].where.path == "$.steps[3].together[1].profile");
  CHECK(errors[0].found == "\"s-curve\"");
  CHECK(errors[0].message == "the s-curve profile needs an acceleration above 0");
}

TEST_CASE("units convert with steps per revolution, microstep and gear ratio") {
  // 200 steps/rev x 8 microsteps x gear 2 = 3200 steps per output turn.
  const MotionFile f = parse_ok(with_steps(R"(
      {"move": {"motor": "m", "by": {"deg": 90}}},
      {"move": {"motor": "m", "by": {"rev": 1}, "speed": {"rpm": 60}}},
      {"move": {"motor": "m", "by": {"steps": -7}, "speed": {"deg_per_s": 9}, "accel": {"deg_per_s2": 45}}},
      {"move": {"motor": "m", "by": 0.6, "profile": "s-curve", "accel": 100}},
      {"move": {"motor": "m", "to": {"deg": -0.1}, "speed": 0.5, "profile": "staged", "stages": 16}},
      {"move": {"motor": "m", "to": 3, "profile": "s-curve", "accel": 10, "jerk": {"deg_per_s3": 36}}})",
                                           R"(, "microstep": 8, "gear_ratio": 2, "speed": {"rpm": 3})"));
  REQUIRE(f.motors.size() == 2);
  CHECK(f.motors[0].speed == Approx(160));  // 3 rpm = 3 x 3200 / 60
  REQUIRE(f.steps.size() == 6);
  CHECK(move_of(f.steps[0]).distance == 800);
  CHECK(move_of(f.steps[0]).profile.speed == Approx(160));
  CHECK(move_of(f.steps[0]).profile.kind == ProfileKind::kConstant);
  CHECK(move_of(f.steps[1]).distance == 3200);
  CHECK(move_of(f.steps[1]).profile.speed == Approx(3200));  // 60 rpm: a turn a second
  CHECK(move_of(f.steps[2]).distance == -7);
  CHECK(move_of(f.steps[2]).profile.speed == Approx(80));
  CHECK(move_of(f.steps[2]).profile.accel == Approx(400));
  CHECK(move_of(f.steps[2]).profile.kind == ProfileKind::kTrapezoid);  // accel given: trapezoid by default
  CHECK(move_of(f.steps[3]).distance == 1);  // rounded to whole steps
  CHECK(move_of(f.steps[3]).profile.jerk == Approx(1000));  // default: accel x 10 /s
  CHECK(move_of(f.steps[4]).absolute);
  CHECK(move_of(f.steps[4]).distance == -1);  // -0.889 steps
  CHECK(move_of(f.steps[4]).profile.kind == ProfileKind::kStaged);
  CHECK(move_of(f.steps[4]).profile.stages == 16);
  CHECK(move_of(f.steps[4]).profile.accel == 0);  // staged with accel 0 is allowed
  CHECK(move_of(f.steps[5]).profile.jerk == Approx(320));
}

TEST_CASE("five different mistakes give exactly five errors, in file order, at the right places") {
  const std::string text = R"({
  "hmc_motion": 1,
  "motors": {
    "pan": {"motor": 1, "microstep": 3},
    "tilt": {"motor": 2, "limits": {"max": 1000}}
  },
  "steps": [
    {"move": {"motor": "pan", "by": 100, "sped": 500}},
    {"move": {"motor": "pna", "by": 100}},
    {"servo": {"id": 1, "angle": 200}},
    {"move": {"motor": "tilt", "to": 1600}}
  ]
}
)";
  const auto errors = parse_errors(text);
  REQUIRE(errors.size() == 5);

  CHECK(errors[0].where.file == "bad.json");
  CHECK(errors[0].where.line == 4);
  CHECK(errors[0].where.column == 38);
  CHECK(errors[0].where.path == "$.motors.pan.microstep");
  CHECK(errors[0].found == "3");
  CHECK(errors[0].expected == "a power of two from 1 to 256");

  CHECK(errors[1].where.line == 8);
  CHECK(errors[1].where.column == 42);
  CHECK(errors[1].where.path == "$.steps[0].move.sped");
  CHECK(errors[1].found == "\"sped\"");
  CHECK(errors[1].message ==
        "unknown key 'sped'; expected one of motor, by, to, speed, accel, profile, stages, jerk, wait (did you mean "
        "'speed'?)");

  CHECK(errors[2].where.line == 9);
  CHECK(errors[2].where.column == 24);
  CHECK(errors[2].where.path == "$.steps[1].move.motor");
  CHECK(errors[2].found == "\"pna\"");
  CHECK(errors[2].message == "unknown motor 'pna' (did you mean 'pan'?)");

  CHECK(errors[3].where.line == 10);
  CHECK(errors[3].where.column == 34);
  CHECK(errors[3].where.path == "$.steps[2].servo.angle");
  CHECK(errors[3].found == "200");

  CHECK(errors[4].where.line == 11);
  CHECK(errors[4].where.column == 38);
  CHECK(errors[4].where.path == "$.steps[3].move.to");
  CHECK(errors[4].found == "1600");
  CHECK(errors[4].message == "position 1600 steps is above tilt's max limit 1000 steps");

  CHECK(errors[1].text() ==
        "bad.json:8:42: $.steps[0].move.sped: unknown key 'sped'; expected one of motor, by, to, speed, accel, "
        "profile, stages, jerk, wait (did you mean 'speed'?) (found \"sped\")");
  CHECK(errors[3].text() ==
        "bad.json:10:34: $.steps[2].servo.angle: angle 200 degrees is out of range (expected a number from 10 to 170 "
        "degrees, found 200)");
}

TEST_CASE("invalid JSON is one error at the problem") {
  SECTION("a missing comma") {
    const auto errors = parse_errors("{\n  \"hmc_motion\": 1,\n  \"motors\": {\"a\": {\"motor\": 1}}\n  \"steps\": []\n}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 4);
    CHECK(errors[0].where.column == 3);
    CHECK(errors[0].where.path == "$");
    CHECK(errors[0].expected == "',' or '}'");
    CHECK(errors[0].found == "\"steps\": []");
    CHECK(errors[0].message.rfind("invalid JSON", 0) == 0);
  }
  SECTION("a trailing comma") {
    const auto errors = parse_errors(with_steps(R"({"wait": {"ms": 1}},)"));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 1);
    CHECK(errors[0].where.column == 99);
    CHECK(errors[0].where.path == "$.steps[1]");
  }
  SECTION("a string left open") {
    const auto errors = parse_errors("{\"hmc_motion\": 1,\n \"name\": \"scan\n}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 2);
    CHECK(errors[0].where.column == 15);
    CHECK(errors[0].where.path == "$.name");
  }
  SECTION("the file ends early") {
    const auto errors = parse_errors("{\"hmc_motion\": 1,");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.column == 18);
    CHECK(errors[0].found == "end of file");
  }
  SECTION("an empty file") {
    const auto errors = parse_errors("  \n");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.line == 2);
    CHECK(errors[0].where.column == 1);
  }
  SECTION("text after the value") {
    const auto errors = parse_errors(with_steps(R"({"wait": {"ms": 1}})") + " x");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].found == "x");
  }
  SECTION("numbers JSON does not allow") {
    for (const char* n : {"01", "1.", "-", "+1", ".5", "1e", "0x10", "NaN", "1e999"}) {
      INFO(n);
      const auto errors = parse_errors(std::string(R"({"hmc_motion": )") + n + "}");
      REQUIRE(errors.size() == 1);
      CHECK(errors[0].message.rfind("invalid JSON", 0) == 0);
    }
  }
  SECTION("bytes that are not UTF-8 in a string") {
    const auto errors = parse_errors("{\"name\": \"caf\xE9\"}");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.column == 14);
    CHECK(errors[0].found == "\\xe9\"}");
  }
}

TEST_CASE("escapes and UTF-8 in strings are read") {
  const MotionFile f = parse_ok(R"({"hmc_motion": 1, "name": "caf\u00e9 \ud83d\ude00 \"q\" \\ 日本",
    "motors": {"m": {"motor": 1}}, "steps": [{"wait": {"ms": 1}}]})");
  CHECK(f.name == "caf\xC3\xA9 \xF0\x9F\x98\x80 \"q\" \\ \xE6\x97\xA5\xE6\x9C\xAC");
}

TEST_CASE("a duplicate key is an error at the second one, and checking goes on") {
  const std::string text = R"({"hmc_motion": 1,
 "motors": {"pan": {"motor": 1, "motor": 2}},
 "steps": [{"servo": {"id": 3, "angle": 90}}]})";
  const auto errors = parse_errors(text);
  REQUIRE(errors.size() == 2);
  CHECK(errors[0].where.line == 2);
  CHECK(errors[0].where.column == 33);
  CHECK(errors[0].where.path == "$.motors.pan.motor");
  CHECK(errors[0].message == "duplicate key \"motor\" (first at line 2, column 21)");
  CHECK(errors[1].where.path == "$.steps[0].servo.id");
}

TEST_CASE("a duplicate key in a large object is found too") {
  std::string text = R"({"hmc_motion": 1, "motors": {"m": {"motor": 1}}, "steps": [{"wait": {"ms": 1}}], "x": {)";
  for (int i = 0; i < 40; ++i) text += "\"k" + std::to_string(i) + "\": 0, ";
  text += "\"k7\": 1}}";
  const auto errors = parse_errors(text);
  REQUIRE(errors.size() == 2);  // the unknown key 'x', and the duplicate inside it
  CHECK(errors[1].where.path == "$.x.k7");
  CHECK(errors[1].message.rfind("duplicate key \"k7\"", 0) == 0);
}

TEST_CASE("nesting is limited, so hostile input cannot exhaust the stack") {
  SECTION("64 levels are read") {
    const auto errors = parse_errors(std::string(64, '[') + std::string(64, ']'));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].message == "a motion file is a JSON object");
  }
  SECTION("65 levels are a syntax error at the 65th bracket") {
    const auto errors = parse_errors(std::string(65, '[') + std::string(65, ']'));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.column == 65);
    CHECK(errors[0].message == "invalid JSON: nested too deeply");
  }
  SECTION("a million levels") {
    const auto errors = parse_errors(std::string(1000000, '{'));
    REQUIRE(errors.size() == 1);
  }
}

TEST_CASE("repeats: their unrolled size and nesting are limited") {
  const std::string step = R"({"wait": {"ms": 1}})";
  const auto repeat = [](int count, const std::string& inner) {
    return R"({"repeat": {"count": )" + std::to_string(count) + R"(, "steps": [)" + inner + "]}}";
  };
  SECTION("exactly a million steps is accepted") {
    const MotionFile f = parse_ok(with_steps(repeat(1000, repeat(1000, step))));
    CHECK(std::get<RepeatStep>(f.steps[0].action).count == 1000);
  }
  SECTION("one more is an error at the repeat that exceeds") {
    const auto errors = parse_errors(with_steps(repeat(1000, repeat(1000, step + "," + step))));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.steps[0].repeat");
    CHECK(errors[0].message == "this repeat unrolls to 2000000 steps");
  }
  SECTION("the file as a whole is limited too") {
    const auto errors = parse_errors(with_steps(repeat(100000, step + "," + step + "," + step + "," + step + "," + step) +
                                                "," + repeat(100000, step + "," + step + "," + step + "," + step + "," + step + "," + step)));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.steps");
    CHECK(errors[0].message == "the file unrolls to 1100000 steps");
  }
  SECTION("eight repeats inside one another are accepted, nine are not") {
    std::string eight = step;
    for (int i = 0; i < 8; ++i) eight = repeat(2, eight);
    parse_ok(with_steps(eight));
    const auto errors = parse_errors(with_steps(repeat(2, eight)));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].message == "repeats nest more than 8 deep");
  }
  SECTION("count out of range") {
    const auto errors = parse_errors(with_steps(repeat(0, step) + "," + repeat(100001, step)));
    REQUIRE(errors.size() == 2);
    CHECK(errors[0].where.path == "$.steps[0].repeat.count");
    CHECK(errors[1].found == "100001");
  }
}

TEST_CASE("the whole-file unroll limit counts a repeat's steps once each") {
  // 1 000 000 exactly with a plain step beside: 1 000 001.
  const auto errors = parse_errors(with_steps(
      R"({"repeat": {"count": 100000, "steps": [{"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}, {"wait": {"ms": 1}}]}}, {"wait": {"ms": 1}})"));
  REQUIRE(errors.size() == 1);
  CHECK(errors[0].message == "the file unrolls to 1000001 steps");
}

TEST_CASE("homing the board's motor 3 is an error naming it") {
  const std::string motors = R"({"hmc_motion": 1, "motors": {"pan": {"motor": 1}, "spin": {"motor": 3}}, "steps": [)";
  SECTION("by name") {
    const auto errors = parse_errors(motors + R"({"home": ["pan", "spin"]}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.steps[0].home");
    CHECK(errors[0].found == "\"spin\"");
    CHECK(errors[0].where.column == 101);
    CHECK(errors[0].message == "'spin' is the board's motor 3, which has no limit switches to home against");
  }
  SECTION("through \"all\"") {
    const auto errors = parse_errors(motors + R"({"home": "all"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].found == "\"all\"");
    CHECK(errors[0].message.find("'spin'") != std::string::npos);
  }
  SECTION("motors 1 and 2 home; motor 3 stops and is waited for") {
    const MotionFile f = parse_ok(motors + R"({"home": "pan"}, {"stop": ["spin"]}, {"wait": {"until_done": "all"}}]})");
    CHECK(std::get<HomeStep>(f.steps[0].action).motors == std::vector<std::string>{"pan"});
    CHECK(std::get<StopStep>(f.steps[1].action).motors == std::vector<std::string>{"spin"});
    CHECK(std::get<WaitStep>(f.steps[2].action).until_done == std::vector<std::string>{"pan", "spin"});
  }
}

TEST_CASE("missing required keys are reported at the object that lacks them, found nothing") {
  SECTION("the top level") {
    const auto errors = parse_errors("{}");
    REQUIRE(errors.size() == 3);
    for (const FileError& e : errors) {
      CHECK(e.where.line == 1);
      CHECK(e.where.column == 1);
      CHECK(e.found == "nothing");
    }
    CHECK(errors[0].where.path == "$.hmc_motion");
    CHECK(errors[1].where.path == "$.motors");
    CHECK(errors[2].where.path == "$.steps");
    CHECK(errors[0].text() == "bad.json:1:1: $.hmc_motion: missing 'hmc_motion' (expected the format version 1, found nothing)");
  }
  SECTION("inside motors and steps") {
    const auto errors = parse_errors(R"({"hmc_motion": 1, "motors": {"m": {}}, "steps": [
      {"move": {"motor": "m"}}, {"servo": {"angle": 90}}, {"led": {"strip": 1}}, {"wait": {}},
      {"repeat": {"steps": [{"stop": "m"}]}}, {"label": "nothing to do"}, {}]})");
    REQUIRE(errors.size() == 8);
    CHECK(errors[0].where.path == "$.motors.m.motor");
    CHECK(errors[1].where.path == "$.steps[0].move.by");
    CHECK(errors[1].message == "a move needs 'by' or 'to'");
    CHECK(errors[2].where.path == "$.steps[1].servo.id");
    CHECK(errors[3].where.path == "$.steps[2].led.colour");
    CHECK(errors[4].where.path == "$.steps[3].wait.ms");
    CHECK(errors[5].where.path == "$.steps[4].repeat.count");
    CHECK(errors[6].where.path == "$.steps[5]");
    CHECK(errors[6].message == "a step needs an action");
    CHECK(errors[7].where.path == "$.steps[6]");
    for (size_t i = 0; i < 6; ++i) CHECK(errors[i].found == "nothing");
    CHECK(errors[6].found == "{\"label\": \"nothing to do\"}");
  }
}

TEST_CASE("found is the value as written, shortened") {
  const auto errors = parse_errors(with_steps(R"({"move": {"motor": "m", "by": 1, "speed": {"deg_per_s":  9000.50 }}},
    {"led": {"strip": 1, "colour": "#12345"}},
    {"servo": {"id": "1", "angle": 90}},
    {"move": {"motor": "m", "by": [1,   2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18]}})"));
  REQUIRE(errors.size() == 4);
  CHECK(errors[0].where.path == "$.steps[0].move.speed.deg_per_s");
  CHECK(errors[0].found == "9000.50");
  CHECK(errors[0].message == "speed 9000.5 deg/s (80004.4 steps/s) is faster than the board's 50000 steps/s");
  CHECK(errors[1].found == "\"#12345\"");
  CHECK(errors[2].found == "\"1\"");
  CHECK(errors[2].message == "expected a whole number from 1 to 2");
  CHECK(errors[2].text().find("(found \"1\")") != std::string::npos);  // "expected" is not said twice
  CHECK(errors[3].found == "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, ...");
}

TEST_CASE("value rules") {
  struct Case {
    const char* steps;
    const char* motor_fields;
    const char* path;
    const char* message_part;
  };
  const Case cases[] = {
      {R"({"move": {"motor": "m", "by": 0.4}})", "", "$.steps[0].move.by", "moves 0 steps"},
      {R"({"move": {"motor": "m", "by": {"deg": 0.01}}})", "", "$.steps[0].move.by.deg", "0.01 deg (0.0888889 steps) moves 0 steps"},
      {R"({"move": {"motor": "m", "by": 1, "to": 2}})", "", "$.steps[0].move.to", "not both"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "trapezoid"}})", "", "$.steps[0].move.profile", "needs an acceleration"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "trapezoid", "accel": 0}})", R"(, "accel": 5)", "$.steps[0].move.profile", "needs an acceleration"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "scurve"}})", "", "$.steps[0].move.profile", "did you mean 's-curve'"},
      {R"({"move": {"motor": "m", "by": 1, "stages": 4}})", "", "$.steps[0].move.stages", "staged profile only"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "staged", "stages": 17}})", "", "$.steps[0].move.stages", "out of range"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "trapezoid", "accel": 5, "jerk": 4}})", "", "$.steps[0].move.jerk", "s-curve profile only"},
      {R"({"move": {"motor": "m", "by": 1, "profile": "s-curve", "accel": 5, "jerk": 0}})", "", "$.steps[0].move.jerk", "not above 0"},
      {R"({"move": {"motor": "m", "by": 1, "speed": 0}})", "", "$.steps[0].move.speed", "not above 0"},
      {R"({"move": {"motor": "m", "by": 1, "speed": 0.01}})", "", "$.steps[0].move.speed", "slower than the board can time"},
      {R"({"move": {"motor": "m", "by": 1, "accel": 2000001}})", "", "$.steps[0].move.accel", "out of range"},
      {R"({"move": {"motor": "m", "by": 1, "speed": {"deg_per_s": 1, "rpm": 1}}})", "", "$.steps[0].move.speed.rpm", "one unit only"},
      {R"({"move": {"motor": "m", "by": {"degs": 1}}})", "", "$.steps[0].move.by.degs", "did you mean 'deg'"},
      {R"({"move": {"motor": "m", "by": {}}})", "", "$.steps[0].move.by", "needs a unit"},
      {R"({"move": {"motor": "m", "by": 3000000000}})", "", "$.steps[0].move.by", "too far"},
      {R"({"move": {"motor": "m", "to": -5}})", R"(, "limits": {"min": 0})", "$.steps[0].move.to", "below m's min limit 0 steps"},
      {R"({"move": {"motor": "m", "by": 1, "wait": 1}})", "", "$.steps[0].move.wait", "expected true or false"},
      {R"({"together": [{"motor": "m", "by": 1}]})", "", "$.steps[0].together", "at least 2 motors"},
      {R"({"together": [{"motor": "m", "by": 1}, {"motor": "m", "by": 2}]})", "", "$.steps[0].together[1].motor", "already moves"},
      {R"({"together": [{"motor": "m", "by": 1, "wait": false}, {"motor": "n", "by": 2}]})", "", "$.steps[0].together[0].wait", "unknown key 'wait'"},
      {R"({"servo": {"id": 3, "angle": 90}})", "", "$.steps[0].servo.id", "servo 3 is out of range"},
      {R"({"servo": {"id": 1, "angle": 1.5e2, "speed": 1}})", "", "$.steps[0].servo.speed", "unknown key"},
      {R"({"led": {"strip": 1, "colour": [1, 2]}})", "", "$.steps[0].led.colour", "3 or 4 values"},
      {R"({"led": {"strip": 1, "colour": [1, 2, 256]}})", "", "$.steps[0].led.colour[2]", "blue 256 is out of range"},
      {R"({"led": {"strip": 1, "colour": "red"}})", "", "$.steps[0].led.colour", "hex digits"},
      {R"({"led": {"strip": 1, "colour": "off", "fade_ms": 3600001}})", "", "$.steps[0].led.fade_ms", "out of range"},
      {R"({"wait": {"ms": 1, "until_done": "m"}})", "", "$.steps[0].wait.until_done", "not both"},
      {R"({"wait": {"ms": -1}})", "", "$.steps[0].wait.ms", "out of range"},
      {R"({"stop": []})", "", "$.steps[0].stop", "names no motor"},
      {R"({"stop": ["m", "m"]})", "", "$.steps[0].stop[1]", "listed twice"},
      {R"({"stop": ["all"]})", "", "$.steps[0].stop[0]", "stands alone"},
      {R"({"servo": {"id": 1, "angle": 90}, "stop": "all"})", "", "$.steps[0].stop", "a step has one action"},
      {R"({"sevro": {"id": 1, "angle": 90}})", "", "$.steps[0].sevro", "did you mean 'servo'"},
      {R"({"wait": {"ms": 1}, "label": 3})", "", "$.steps[0].label", "expected a string"},
      {R"(3)", "", "$.steps[0]", "expected a step"},
      {R"({"home": "m"})", R"(, "microstep": 12)", "$.motors.m.microstep", "microstep 12 is not a power of two"},
      {R"({"home": "m"})", R"(, "microstep": 512)", "$.motors.m.microstep", "microstep 512 is out of range"},
      {R"({"home": "m"})", R"(, "gear_ratio": 1e308)", "$.motors.m.gear_ratio", "out of range"},
      {R"({"home": "m"})", R"(, "steps_per_rev": 0)", "$.motors.m.steps_per_rev", "out of range"},
      {R"({"home": "m"})", R"(, "gear_ratio": 0)", "$.motors.m.gear_ratio", "not above 0"},
      {R"({"home": "m"})", R"(, "speed": {"rpm": 1000})", "$.motors.m.speed.rpm", "faster than the board's"},
      {R"({"home": "m"})", R"(, "limits": {"min": 5, "max": 5})", "$.motors.m.limits.max", "not above min"},
      {R"({"home": "m"})", R"(, "limit": {})", "$.motors.m.limit", "did you mean 'limits'"},
  };
  for (const Case& c : cases) {
    INFO(c.steps << " / motor" << c.motor_fields);
    const auto errors = parse_errors(with_steps(c.steps, c.motor_fields));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == c.path);
    CHECK(errors[0].message.find(c.message_part) != std::string::npos);
  }
}

TEST_CASE("the top level and motors") {
  SECTION("a version this reader does not know") {
    const auto errors = parse_errors(R"({"hmc_motion": 2, "motors": {"m": {"motor": 1}}, "steps": [{"stop": "m"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.hmc_motion");
  }
  SECTION("four motors, two on one board motor, and a reserved name") {
    const auto errors = parse_errors(R"({"hmc_motion": 1, "motors": {"a": {"motor": 1}, "b": {"motor": 1},
      "all": {"motor": 2}, "d": {"motor": 3}}, "steps": [{"stop": "a"}]})");
    REQUIRE(errors.size() == 3);
    CHECK(errors[0].where.path == "$.motors");
    CHECK(errors[0].message == "the board has 3 steppers; 4 are declared");
    CHECK(errors[1].where.path == "$.motors.b.motor");
    CHECK(errors[1].message == "motor 1 is already 'a'");
    CHECK(errors[2].where.path == "$.motors.all");
  }
  SECTION("broken motors: names are not reported again") {
    const auto errors = parse_errors(R"({"hmc_motion": 1, "motors": 3, "steps": [{"stop": "a"}, {"home": "b"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.motors");
  }
  SECTION("a motor with broken gearing: its unit conversions are not reported again") {
    const auto errors = parse_errors(with_steps(R"({"move": {"motor": "m", "by": {"deg": 1000000}}})", R"(, "microstep": 3)"));
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.motors.m.microstep");
  }
  SECTION("names outside plain identifiers get bracketed paths") {
    const auto errors = parse_errors(R"({"hmc_motion": 1, "motors": {"left arm": {"motor": 5}}, "steps": [{"stop": "all"}]})");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].where.path == "$.motors[\"left arm\"].motor");
  }
}

TEST_CASE("errors come sorted by position, every one of them") {
  const auto errors = parse_errors(R"({"steps": [{"servo": {"id": 9, "angle": 900}}], "hmc_motion": 7,
    "motors": {"m": {"motor": 0}}})");
  REQUIRE(errors.size() == 4);
  for (size_t i = 1; i < errors.size(); ++i) {
    const bool ordered = errors[i - 1].where.line < errors[i].where.line ||
                         (errors[i - 1].where.line == errors[i].where.line && errors[i - 1].where.column <= errors[i].where.column);
    CHECK(ordered);
  }
  CHECK(errors[0].where.path == "$.steps[0].servo.id");
  CHECK(errors[3].where.path == "$.motors.m.motor");
}

TEST_CASE("load_motion_file reads a file, and an unreadable one is one error") {
  const auto r = load_motion_file("/nonexistent/dir/file.json");
  REQUIRE_FALSE(r.ok());
  REQUIRE(r.error().size() == 1);
  CHECK(r.error()[0].where.line == 0);
  CHECK(r.error()[0].text().rfind("/nonexistent/dir/file.json: cannot read the file: ", 0) == 0);

  const auto dir = load_motion_file(HMC_DOCS_DIR);
  REQUIRE_FALSE(dir.ok());
  CHECK(dir.error().size() == 1);
}

TEST_CASE("docs/motion-files.md shows the tested example, and the schema is JSON") {
  std::ifstream doc(HMC_DOCS_DIR "/motion-files.md");
  REQUIRE(doc);
  std::stringstream text;
  text << doc.rdbuf();
  const std::string md = text.str();
  const std::string fence = "```json\n";
  const auto begin = md.find(fence);
  REQUIRE(begin != std::string::npos);
  const auto end = md.find("```", begin + fence.size());
  REQUIRE(end != std::string::npos);
  CHECK(md.substr(begin + fence.size(), end - begin - fence.size()) == kExample);

  // Every other JSON block of the doc is a valid file too, unless it says it is not.
  size_t at = end;
  int checked = 0;
  while ((at = md.find(fence, at)) != std::string::npos) {
    const auto close = md.find("```", at + fence.size());
    REQUIRE(close != std::string::npos);
    const std::string block = md.substr(at + fence.size(), close - at - fence.size());
    const auto line_start = md.rfind('\n', at - 2);
    const std::string before = md.substr(line_start + 1, at - line_start - 1);
    if (block.find("\"hmc_motion\"") != std::string::npos && before.find("not valid") == std::string::npos) {
      INFO(block);
      parse_ok(block);
      ++checked;
    }
    at = close + 3;
  }
  CHECK(checked > 0);

  std::ifstream schema_file(HMC_DOCS_DIR "/motion-file.schema.json");
  REQUIRE(schema_file);
  const auto schema = nlohmann::json::parse(schema_file, nullptr, false);
  REQUIRE_FALSE(schema.is_discarded());
  CHECK(schema.at("$schema") == "https://json-schema.org/draft/2020-12/schema");
}
