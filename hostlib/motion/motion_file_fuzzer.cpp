// Fuzzes motion files: arbitrary bytes through parse_motion_file() (the position-keeping JSON
// reader and every check of the format), then plan_motion() on each file it accepts. Besides
// crashes, hangs and undefined behaviour it checks:
//   - a refused file has at least one error; each names the file, has a line and column of
//     at least 1 and at most one past the input's last line, a path starting with "$" and a
//     message, and renders with text() on one line; the errors come sorted by position;
//   - an accepted file keeps the format's promises: version 1; 1-3 motors, each a distinct
//     board motor 1-3 with a power-of-two microstep 1-256, 1-100 000 full steps per turn, a
//     finite gear ratio above 0, a default speed within (0, 50 000] steps/s, an acceleration
//     within [0, 2 000 000] and min < max limits; every step (repeats included, at most 8 deep)
//     has a location with line >= 1 and a path; moves name declared motors, move whole steps
//     within what one STM counts (relative moves never 0, absolute ones within the limits),
//     with a speed in range and a profile that fits its acceleration; repeat counts 1-100 000
//     and at most 1 000 000 steps unrolled; servo, strip and colour values in range;
//   - plan_motion() (PlanOptions{}, every start position 0) returns, and a refusal has errors,
//     for accepted files of at most kPlanLimit unrolled steps (longer ones only cost time);
//   - notes (values rounded to a whole step) have a location as errors do.
// A file that names a profile ("profile": any name) gets kProfile, a rig with a linear axis and
// an inverted rotary one, so the profile's units and directions are fuzzed without the disk.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <variant>

#include "hmc/protocol_facts.h"
#include "fuzz_support.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"

namespace {

namespace proto = hmc::proto;
using hmc::fuzz::require;
using namespace hmc::motion;

constexpr uint64_t kPlanLimit = 2000;

constexpr const char* kProfile = R"(
[axis.slide]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
limits = ["0mm", "310mm"]
speed = "50mm/s"
accel = "200mm/s2"

[axis.tilt]
motor = 2
gear_ratio = 2
rotary = true
invert = true
limits = ["-180deg", "0deg"]

[axis.z]
motor = 3
microstep = 4
screw_lead = "8mm"
)";

hmc::Result<hmc::Profile, std::string> fuzz_profile(const std::string&, const std::string&) {
  static const auto profile = hmc::parse_profile(kProfile, "fuzz.toml");
  if (!profile) return std::string("the fuzz profile has mistakes: ") + profile.error().text();
  return profile.value();
}

struct Checker {
  std::string_view input;
  const MotionFile& file;

  void check(bool holds, const std::string& what) const {
    require(holds, [&] { return what; }, input);
  }

  void location(const Location& where, const std::string& what) const {
    check(where.line >= 1 && where.column >= 1, what + ": location " + std::to_string(where.line) + ":" +
                                                    std::to_string(where.column) + " is not 1-based");
    check(where.file == "fuzz.json", what + ": location names file '" + where.file + "'");
    check(!where.path.empty() && where.path[0] == '$', what + ": path '" + where.path + "'");
  }

  const MotorConfig& motor_of(const Move& m) const {
    const MotorConfig* c = file.motor(m.motor);
    check(c != nullptr, "a move names motor '" + m.motor + "', which the file does not declare");
    return *c;
  }

  void move(const Move& m) const {
    location(m.where, "move");
    const MotorConfig& c = motor_of(m);
    check(m.distance == std::round(m.distance) && std::fabs(m.distance) <= proto::kIntMax,
          "move distance " + std::to_string(m.distance) + " is not a whole number of steps in range");
    if (!m.absolute) check(m.distance != 0, "a relative move of 0 steps was accepted");
    if (m.absolute && c.min_position) check(m.distance >= *c.min_position, "a 'to' below the motor's min was accepted");
    if (m.absolute && c.max_position) check(m.distance <= *c.max_position, "a 'to' above the motor's max was accepted");
    const Profile& p = m.profile;
    check(p.speed > 0 && p.speed <= 50000, "move speed " + std::to_string(p.speed) + " out of range");
    check(p.accel >= 0 && p.accel <= 2000000, "move accel " + std::to_string(p.accel) + " out of range");
    if (p.kind == ProfileKind::kTrapezoid || p.kind == ProfileKind::kSCurve) {
      check(p.accel > 0, "a trapezoid or s-curve without acceleration was accepted");
    }
    if (p.kind == ProfileKind::kSCurve) check(p.jerk > 0 && std::isfinite(p.jerk), "s-curve jerk not above 0");
    if (p.kind == ProfileKind::kStaged) check(p.stages >= 2 && p.stages <= 16, "stages out of range");
  }

  void names(const std::vector<std::string>& list, const char* what) const {
    for (const std::string& n : list) {
      check(file.motor(n) != nullptr, std::string(what) + " names motor '" + n + "', which the file does not declare");
    }
  }

  void colour(const Colour& c) const {
    check(c.r <= 255 && c.g <= 255 && c.b <= 255 && c.w <= 255, "a colour value above 255");
  }

  // Returns the unrolled size of the steps.
  uint64_t steps(const std::vector<Step>& list, int depth) const {
    check(!list.empty(), "an empty list of steps was accepted");
    check(depth <= 8, "repeats nest deeper than 8");
    uint64_t total = 0;
    for (const Step& s : list) {
      location(s.where, "step");
      total += std::visit([&](const auto& a) { return action(a, depth); }, s.action);
    }
    return total;
  }

  uint64_t action(const HomeStep& a, int) const {
    check(!a.motors.empty(), "a home of no motor");
    names(a.motors, "home");
    for (const std::string& n : a.motors) check(proto::motor_has_switches(file.motor(n)->motor), "motor 3 homed");
    return 1;
  }
  uint64_t action(const MoveStep& a, int) const {
    move(a.move);
    return 1;
  }
  uint64_t action(const TogetherStep& a, int) const {
    check(a.moves.size() >= 2, "a together step of fewer than 2 moves");
    std::set<std::string> motors;
    for (const Move& m : a.moves) {
      move(m);
      check(motors.insert(m.motor).second, "a together step moves '" + m.motor + "' twice");
    }
    return 1;
  }
  uint64_t action(const ServoStep& a, int) const {
    check(a.servo >= 1 && a.servo <= proto::kServoCount, "servo id out of range");
    check(a.angle >= proto::kServoFields[1].min && a.angle <= proto::kServoFields[1].max, "servo angle out of range");
    return 1;
  }
  uint64_t action(const LedStep& a, int) const {
    check(a.strip >= 1 && a.strip <= proto::kStripCount, "strip out of range");
    colour(a.colour);
    if (a.from) colour(*a.from);
    check(a.fade_ms >= 0 && a.fade_ms <= 3600000, "fade_ms out of range");
    return 1;
  }
  uint64_t action(const WaitStep& a, int) const {
    check(a.ms >= 0 && a.ms <= 86400000, "wait ms out of range");
    names(a.until_done, "wait");
    return 1;
  }
  uint64_t action(const StopStep& a, int) const {
    names(a.motors, "stop");
    return 1;
  }
  uint64_t action(const RepeatStep& a, int depth) const {
    check(a.count >= 1 && a.count <= 100000, "repeat count " + std::to_string(a.count) + " out of range");
    return a.count * steps(a.steps, depth + 1);
  }

  uint64_t all() const {
    check(file.version == 1, "version is not 1");
    check(!file.motors.empty() && file.motors.size() <= proto::kMotorCount, "motor count out of range");
    std::set<uint32_t> board;
    for (const MotorConfig& c : file.motors) {
      location(c.where, "motor");
      check(c.motor >= 1 && c.motor <= proto::kMotorCount, "board motor out of range");
      check(board.insert(c.motor).second, "board motor used twice");
      check(proto::is_power_of_two(c.microstep) && c.microstep <= 256, "microstep not a power of two 1-256");
      check(c.full_steps_per_rev >= 1 && c.full_steps_per_rev <= 100000, "steps_per_rev out of range");
      check(c.gear_ratio > 0 && std::isfinite(c.gear_ratio), "gear ratio not above 0");
      check(c.steps_per_degree() > 0 && std::isfinite(c.steps_per_degree()), "steps per degree not finite above 0");
      check(c.speed > 0 && c.speed <= 50000, "motor speed out of range");
      check(c.accel >= 0 && c.accel <= 2000000, "motor accel out of range");
      if (c.min_position && c.max_position) check(*c.min_position < *c.max_position, "limits min >= max");
      check(c.name != "all" && !c.name.empty(), "motor name '" + c.name + "' accepted");
    }
    const uint64_t unrolled = steps(file.steps, 0);
    check(unrolled <= 1000000, "the file unrolls to " + std::to_string(unrolled) + " steps");
    return unrolled;
  }
};

void check_errors(std::string_view input, const std::vector<FileError>& errors) {
  require(!errors.empty(), [] { return std::string("a refusal without errors"); }, input);
  uint32_t lines = 1;
  for (char c : input) lines += c == '\n' ? 1 : 0;
  const FileError* previous = nullptr;
  for (const FileError& e : errors) {
    const std::string text = e.text();
    require(e.where.file == "fuzz.json" && e.where.line >= 1 && e.where.line <= lines && e.where.column >= 1 &&
                !e.where.path.empty() && e.where.path[0] == '$' && !e.message.empty() &&
                text.find_first_of("\r\n") == std::string::npos,
            [&] { return "a malformed error: " + text; }, input);
    if (previous != nullptr) {
      const bool sorted = previous->where.line < e.where.line ||
                          (previous->where.line == e.where.line && previous->where.column <= e.where.column);
      require(sorted, [&] { return "errors out of order: " + previous->text() + " then " + text; }, input);
    }
    previous = &e;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  ReadOptions read;
  read.load_profile = fuzz_profile;
  const auto parsed = parse_motion_file(text, "fuzz.json", read);
  if (!parsed) {
    check_errors(text, parsed.error());
    return 0;
  }
  const MotionFile& file = parsed.value();
  const uint64_t unrolled = Checker{text, file}.all();
  for (const FileError& n : file.notes) Checker{text, file}.location(n.where, "note");
  if (unrolled > kPlanLimit) return 0;

  PlanOptions options;
  for (auto& p : options.start_position) p = 0;
  const auto plan = plan_motion(file, options);
  if (!plan) {
    require(!plan.error().empty(), [] { return std::string("plan_motion refused without errors"); }, text);
    for (const FileError& e : plan.error()) (void)e.text();
  }
  return 0;
}
