// Internal to the motion module: the parts that read a motion file (motion_file.h), each over the
// JSON reader's positioned values (json_reader.h):
//   Reporter        collects mistakes with where they are, and reads typed values (the words
//                   messages use for numbers, names and suggestions: motion_file_report.cpp);
//   QuantityReader  unit conversion: distances, speeds, accelerations and jerks in their units,
//                   to steps, and the board's ranges for them (motion_units.cpp);
//   MotorTable      the file's "motors": numbers, gearing, defaults, limits, and the names steps
//                   use (motion_motors.cpp);
//   StepChecker     the steps and their actions, checked against the format and the board's
//                   rules (motion_steps.cpp).
// motion_file.cpp reads the document and its top level with them. Each part uses only the ones
// listed above it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/motion_file.h"
#include "hmc/profile.h"
#include "hmc/protocol_facts.h"
#include "json_reader.h"

namespace hmc::motion::reading {

using json::Value;
using Kind = json::Value::Kind;

// The board's rules (docs/protocol.md, "What the board does" and the settings table).
constexpr double kMaxRate = proto::kSettings[proto::kSettingMaxRate - 1].max;  // 50 000 steps/s
constexpr double kMinDelayUs = 5;
constexpr double kMaxDelayUs = 89e6;
constexpr double kMinRate = 1e6 / kMaxDelayUs;  // one step per 89 s: the slowest the board times
constexpr double kMaxAccel = proto::kSettings[proto::kSettingAccel - 1].max;  // 2 000 000 steps/s²
constexpr double kMaxSteps = proto::kIntMax;  // what one STM counts; positions stay within it too
constexpr uint32_t kMinServoAngle = proto::kServoFields[1].min;
constexpr uint32_t kMaxServoAngle = proto::kServoFields[1].max;
static_assert(1e6 / kMaxRate >= kMinDelayUs, "the rate limit keeps the delay at or above 5 us");

// The format's own limits (docs/motion-files.md).
constexpr uint32_t kMaxStepsPerRev = 100000;
constexpr uint32_t kMaxMicrostep = 256;
constexpr uint32_t kMinStages = 2;
constexpr uint32_t kMaxStages = 16;
constexpr uint32_t kMaxRepeatCount = 100000;
constexpr int kMaxRepeatDepth = 8;
constexpr uint64_t kMaxUnrolledSteps = 1000000;
constexpr double kMaxFadeMs = 3600000;
constexpr double kMaxWaitMs = 86400000;
constexpr double kJerkPerAccel = 10;  // default jerk: full acceleration reached in 0.1 s
constexpr double kWholeStep = 1e-6;   // closer to a whole step than this is that step (not "rounded")

// A fixed list of keys (or names), for membership, messages and suggestions.
struct Keys {
  const std::string_view* data;
  size_t size;
  template <size_t N>
  constexpr Keys(const std::string_view (&keys)[N]) : data(keys), size(N) {}  // NOLINT: implicit by design
  const std::string_view* begin() const { return data; }
  const std::string_view* end() const { return data + size; }
  bool contains(std::string_view key) const { return std::find(begin(), end(), key) != end(); }
  std::string list() const {
    std::string out;
    for (std::string_view k : *this) out += (out.empty() ? "" : ", ") + std::string(k);
    return out;
  }
};

constexpr std::string_view kMotorKeys[] = {"motor", "steps_per_rev", "microstep", "gear_ratio",
                                           "speed", "accel",         "limits"};
constexpr std::string_view kLimitKeys[] = {"min", "max"};
constexpr std::string_view kMoveKeys[] = {"motor", "by", "to", "speed", "accel", "profile", "stages", "jerk", "wait"};
constexpr std::string_view kTogetherMoveKeys[] = {"motor", "by", "to", "speed", "accel", "profile", "stages", "jerk"};
constexpr std::string_view kActions[] = {"home", "move", "together", "servo", "led", "wait", "repeat", "stop"};
constexpr std::string_view kStepKeys[] = {"home", "move",   "together", "servo", "led",
                                          "wait", "repeat", "stop",     "label"};
constexpr std::string_view kServoKeys[] = {"id", "angle"};
constexpr std::string_view kLedKeys[] = {"strip", "colour", "from", "fade_ms"};
constexpr std::string_view kWaitKeys[] = {"ms", "until_done"};
constexpr std::string_view kRepeatKeys[] = {"count", "steps"};
constexpr std::string_view kProfiles[] = {"constant", "staged", "trapezoid", "s-curve"};
constexpr ProfileKind kProfileKinds[] = {ProfileKind::kConstant, ProfileKind::kStaged, ProfileKind::kTrapezoid,
                                         ProfileKind::kSCurve};

// Numbers for messages: whole numbers in full, others to 6 significant digits.
std::string fmt(double v);
// Names and keys as messages show them: on one line, control bytes escaped, long ones cut.
std::string shown(std::string_view s);
std::string single_quoted(std::string_view s);
// Optimal string alignment distance (edits, with swaps of neighbours), for suggestions only.
size_t edit_distance(std::string_view a, std::string_view b);

// " (did you mean 'speed'?)" for the closest candidate within 2 edits, or nothing.
template <typename Names>
std::string suggestion(std::string_view word, const Names& candidates) {
  if (word.size() > 64) return {};
  size_t best = 3;
  std::string_view pick;
  for (std::string_view c : candidates) {
    const size_t d = edit_distance(word, c);
    if (d < best && d < std::max(word.size(), c.size())) {
      best = d;
      pick = c;
    }
  }
  return pick.empty() ? std::string() : " (did you mean " + single_quoted(pick) + "?)";
}

// Collects the mistakes of one file, each with where it is, and reads typed values, reporting
// those of the wrong type or range.
class Reporter {
 public:
  Reporter(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  std::vector<FileError>& errors() { return errors_; }
  size_t count() const { return errors_.size(); }
  // Notes: what is not a mistake but worth saying (a value rounded to a whole step).
  std::vector<FileError>& notes() { return notes_; }
  void note(const Value& v, const std::string& path, std::string message) {
    notes_.push_back(FileError{location(v.at, path), {}, {}, std::move(message)});
  }

  // ---- errors

  Location location(const json::Position& at, std::string path) const {
    return Location{file_, at.line, at.column, std::move(path)};
  }
  std::string found(const Value& v) const { return json::excerpt(text_, v.at.offset, v.end); }
  std::string found(const json::Member& m) const { return json::excerpt(text_, m.at.offset, m.end); }

  void add(const json::Position& at, std::string path, std::string expected, std::string found_text,
           std::string message) {
    FileError e;
    e.where = location(at, std::move(path));
    e.expected = std::move(expected);
    e.found = std::move(found_text);
    e.message = std::move(message);
    errors_.push_back(std::move(e));
  }
  // A wrong value: points at it and quotes it.
  void bad(const Value& v, const std::string& path, std::string expected, std::string message) {
    add(v.at, path, std::move(expected), found(v), std::move(message));
  }
  // A wrong shape: "expected X" is the whole message.
  void wrong_type(const Value& v, const std::string& path, const std::string& expected) {
    bad(v, path, expected, "expected " + expected);
  }
  // A missing key: points at the object that lacks it.
  void missing(const Value& object, const std::string& path, std::string_view key, std::string expected) {
    add(object.at, json::path_with_key(path, key), std::move(expected), "nothing", "missing " + single_quoted(key));
  }

  // Reports every key of `object` not in `keys`; true when there are none.
  bool known_keys(const Value& object, const std::string& path, Keys keys) {
    bool ok = true;
    for (const json::Member& m : object.members) {
      if (keys.contains(m.key)) continue;
      ok = false;
      const std::string expected = "one of " + keys.list();
      add(m.at, json::path_with_key(path, m.key), expected, found(m),
          "unknown key " + single_quoted(m.key) + "; expected " + expected + suggestion(m.key, keys));
    }
    return ok;
  }

  // ---- typed values

  const Value* get(const Value& object, std::string_view key) const {
    const json::Member* m = object.find(key);
    return m == nullptr ? nullptr : &m->value;
  }

  std::optional<uint32_t> integer(const Value& v, const std::string& path, std::string_view what, uint32_t min,
                                  uint32_t max) {
    const std::string expected = "a whole number from " + fmt(min) + " to " + fmt(max);
    if (!v.is(Kind::kNumber)) {
      wrong_type(v, path, expected);
      return std::nullopt;
    }
    if (v.number != std::floor(v.number)) {
      bad(v, path, expected, std::string(what) + " " + fmt(v.number) + " is not a whole number");
      return std::nullopt;
    }
    if (v.number < min || v.number > max) {
      bad(v, path, expected, std::string(what) + " " + fmt(v.number) + " is out of range");
      return std::nullopt;
    }
    return static_cast<uint32_t>(v.number);
  }

  // A number within [min, max].
  std::optional<double> number(const Value& v, const std::string& path, std::string_view what, double min, double max,
                               const std::string& unit) {
    const std::string expected = "a number from " + fmt(min) + " to " + fmt(max) + unit;
    if (!v.is(Kind::kNumber)) {
      wrong_type(v, path, expected);
      return std::nullopt;
    }
    if (v.number < min || v.number > max) {
      bad(v, path, expected, std::string(what) + " " + fmt(v.number) + unit + " is out of range");
      return std::nullopt;
    }
    return v.number;
  }

  std::optional<std::string> string(const Value& v, const std::string& path) {
    if (!v.is(Kind::kString)) {
      wrong_type(v, path, "a string");
      return std::nullopt;
    }
    return v.string;
  }

 private:
  std::string_view text_;
  const std::string& file_;
  std::vector<FileError> errors_;
  std::vector<FileError> notes_;
};

// Quantities: a plain number is the base unit; an object names one unit.
enum class Dim : uint8_t { kDistance, kSpeed, kAccel, kJerk };

// How one motor's units become steps.
struct Scale {
  double per_degree = 0;  // steps per output degree; 0: the gearing is unknown or broken
  double per_mm = 0;      // steps per mm on a linear axis of a profile, whose units are mm, not deg
  double sign = 1;        // -1: the profile inverts the axis (distances and positions in its sense)
};

// A quantity as read: the value in the base unit and where its number is.
struct Quantity {
  double value = 0;
  const Value* node = nullptr;  // the number
  std::string path;             // of the number
  std::string written;          // "90 deg/s"
  bool base = true;             // given in the base unit
};

// Unit conversion: a quantity as written, in the base unit, and the board's ranges for it.
class QuantityReader {
 public:
  explicit QuantityReader(Reporter& r) : r_(r) {}

  // A quantity in the base unit. With the motor's gearing unknown or broken (scale.per_degree 0),
  // degrees, millimetres and revolutions are read but not converted (nothing is returned, and
  // nothing reported for it). A linear axis of a profile takes mm where others take deg.
  std::optional<Quantity> quantity(const Value& v, const std::string& path, Dim dim, const Scale& scale);
  // "90 deg/s (800 steps/s)" or "800 steps/s".
  static std::string described(const Quantity& q, const char* base_unit);
  bool speed_ok(const Quantity& q);
  bool accel_ok(const Quantity& q);
  // A distance or position, within what one STM counts.
  bool steps_ok(const Quantity& q, double rounded);

 private:
  Reporter& r_;
};

// One motor of "motors" while checking: its config, and whether the fields degrees and
// revolutions depend on are sound (if not, unit conversions for it are not checked).
struct MotorEntry {
  MotorConfig config;
  bool scale_ok = true;
  bool number_ok = true;
  bool accel_ok = true;  // its default acceleration is what the file says
  double steps_per_mm = 0;  // a linear axis of a profile
  double sign = 1;          // -1: an axis the profile inverts

  Scale scale() const { return scale_ok ? Scale{config.steps_per_degree(), steps_per_mm, sign} : Scale{}; }
};

// The file's "motors", and the motor names steps use.
class MotorTable {
 public:
  MotorTable(Reporter& r, QuantityReader& q) : r_(r), q_(q) {}

  // Reads "motors" into `out` (every declared motor, a broken one too).
  void read(const Value& v, const std::string& path, std::vector<MotorConfig>& out);
  // Takes the motors from a machine profile instead: one per axis, named as the axis, with its
  // gearing, units, direction, default speed and acceleration and soft limits.
  void from_profile(const hmc::Profile& profile, const Location& where, std::vector<MotorConfig>& out);

  const MotorEntry* find_motor(std::string_view name) const;
  // A reference to a declared motor. With "motors" itself broken, names are not checked.
  const MotorEntry* motor_ref(const Value& v, const std::string& path, bool allow_all);

  struct Names {
    std::vector<std::string> names;
    std::vector<const Value*> nodes;  // where each name is written ("all" for all of them)
    bool all = false;
  };
  // A motor name, a list of names, or "all" (every declared motor, in file order).
  std::optional<Names> motor_names(const Value& v, const std::string& path);

 private:
  MotorEntry motor(const Value& v, const std::string& path, const std::string& name,
                   std::map<uint32_t, std::string>& numbers);
  void limits(const Value& v, const std::string& path, const Scale& scale, MotorConfig& c);
  std::string declared_names() const;

  Reporter& r_;
  QuantityReader& q_;
  std::vector<MotorEntry> motors_;
  bool motors_known_ = false;  // "motors" is an object: names can be checked against it
};

// The steps: each action checked, into the steps of a MotionFile.
class StepChecker {
 public:
  StepChecker(Reporter& r, QuantityReader& q, MotorTable& motors) : r_(r), q_(q), motors_(motors) {}

  // Checks a list of steps into `out`; returns how many steps they unroll to.
  uint64_t steps(const Value& list, const std::string& path, int repeat_depth, std::vector<Step>& out);
  // Where the broken steps that may move motors are: each stands in the steps as an empty wait
  // (a placeholder), so that planning the rest can tell where positions stop being followed.
  const std::vector<Location>& broken() const { return broken_; }

 private:
  // One step; returns its unrolled size (0 when it yields no step).
  uint64_t step(const Value& v, const std::string& path, int repeat_depth, std::vector<Step>& out);
  bool home(const Value& v, const std::string& path, Step& s);
  bool stop(const Value& v, const std::string& path, Step& s);
  bool move_step(const Value& v, const std::string& path, Step& s);
  bool together(const Value& v, const std::string& path, Step& s);
  std::optional<Move> move(const Value& v, const std::string& path, bool in_together, bool& wait);
  bool servo(const Value& v, const std::string& path, Step& s);
  std::optional<Colour> colour(const Value& v, const std::string& path);
  bool led(const Value& v, const std::string& path, Step& s);
  bool wait(const Value& v, const std::string& path, Step& s);
  // Returns the repeat's unrolled size, 0 when it is broken.
  uint64_t repeat(const Value& v, const std::string& path, int repeat_depth, Step& s);

  Reporter& r_;
  QuantityReader& q_;
  MotorTable& motors_;
  std::vector<Location> broken_;
  bool unconverted_ = false;  // a distance of this step could not be converted (its motor's gearing is broken)
};

}  // namespace hmc::motion::reading
