// Motion files (motion_file.h, docs/motion-files.md): reads the JSON with positions
// (json_reader.h), checks every key and value against the format and the board's rules,
// converts distances and rates to steps, and collects every mistake with where it is.
//
// Checking goes on after a mistake: a broken value yields no step, and what depends on it
// (unit conversions of a motor whose gearing is broken, names when "motors" is missing) is not
// checked, so one mistake is reported once.
#include "hmc/motion_file.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <set>
#include <string_view>
#include <system_error>
#include <utility>

#include "hmc/protocol_facts.h"
#include "json_reader.h"

namespace hmc::motion {

namespace {

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

constexpr std::string_view kTopKeys[] = {"hmc_motion", "name", "motors", "steps"};
constexpr std::string_view kMotorKeys[] = {"motor", "steps_per_rev", "microstep", "gear_ratio", "speed", "accel", "limits"};
constexpr std::string_view kLimitKeys[] = {"min", "max"};
constexpr std::string_view kMoveKeys[] = {"motor", "by", "to", "speed", "accel", "profile", "stages", "jerk", "wait"};
constexpr std::string_view kTogetherMoveKeys[] = {"motor", "by", "to", "speed", "accel", "profile", "stages", "jerk"};
constexpr std::string_view kActions[] = {"home", "move", "together", "servo", "led", "wait", "repeat", "stop"};
constexpr std::string_view kStepKeys[] = {"home", "move", "together", "servo", "led", "wait", "repeat", "stop", "label"};
constexpr std::string_view kServoKeys[] = {"id", "angle"};
constexpr std::string_view kLedKeys[] = {"strip", "colour", "from", "fade_ms"};
constexpr std::string_view kWaitKeys[] = {"ms", "until_done"};
constexpr std::string_view kRepeatKeys[] = {"count", "steps"};
constexpr std::string_view kProfiles[] = {"constant", "staged", "trapezoid", "s-curve"};
constexpr ProfileKind kProfileKinds[] = {ProfileKind::kConstant, ProfileKind::kStaged, ProfileKind::kTrapezoid,
                                         ProfileKind::kSCurve};

// Quantities: a plain number is the base unit; an object names one unit.
enum class Dim : uint8_t { kDistance, kSpeed, kAccel, kJerk };
struct Unit {
  std::string_view key;
  double degrees;  // output degrees per unit; 0: the base unit (steps...)
  const char* label;
};
constexpr Unit kDistanceUnits[] = {{"steps", 0, "steps"}, {"deg", 1, "deg"}, {"rev", 360, "rev"}};
constexpr Unit kSpeedUnits[] = {{"steps_per_s", 0, "steps/s"}, {"deg_per_s", 1, "deg/s"}, {"rpm", 6, "rpm"}};
constexpr Unit kAccelUnits[] = {{"steps_per_s2", 0, "steps/s²"}, {"deg_per_s2", 1, "deg/s²"}};
constexpr Unit kJerkUnits[] = {{"steps_per_s3", 0, "steps/s³"}, {"deg_per_s3", 1, "deg/s³"}};
constexpr std::string_view kDistanceKeys[] = {"steps", "deg", "rev"};
constexpr std::string_view kSpeedKeys[] = {"steps_per_s", "deg_per_s", "rpm"};
constexpr std::string_view kAccelKeys[] = {"steps_per_s2", "deg_per_s2"};
constexpr std::string_view kJerkKeys[] = {"steps_per_s3", "deg_per_s3"};

struct DimInfo {
  const Unit* units;
  size_t count;
  Keys keys;
  const char* expected;  // the shapes it takes
};
DimInfo dim_info(Dim dim) {
  switch (dim) {
    case Dim::kDistance:
      return {kDistanceUnits, 3, kDistanceKeys, "a number of steps, or an object with one of steps, deg, rev"};
    case Dim::kSpeed:
      return {kSpeedUnits, 3, kSpeedKeys, "a number of steps/s, or an object with one of steps_per_s, deg_per_s, rpm"};
    case Dim::kAccel:
      return {kAccelUnits, 2, kAccelKeys, "a number of steps/s², or an object with one of steps_per_s2, deg_per_s2"};
    case Dim::kJerk:
      break;
  }
  return {kJerkUnits, 2, kJerkKeys, "a number of steps/s³, or an object with one of steps_per_s3, deg_per_s3"};
}

// Numbers for messages: whole numbers in full, others to 6 significant digits.
std::string fmt(double v) {
  if (std::isfinite(v) && std::fabs(v) < 1e15 && v == std::floor(v)) return std::to_string(static_cast<long long>(v));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Names and keys as messages show them: on one line, control bytes escaped, long ones cut.
std::string shown(std::string_view s) { return json::excerpt(s, 0, s.size()); }
std::string quoted(std::string_view s) { return "'" + shown(s) + "'"; }

// Optimal string alignment distance (edits, with swaps of neighbours), for suggestions only.
size_t edit_distance(std::string_view a, std::string_view b) {
  if (a.size() > b.size() + 2 || b.size() > a.size() + 2) return 3;  // too far apart to suggest
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

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
  return pick.empty() ? std::string() : " (did you mean " + quoted(pick) + "?)";
}

// One motor of "motors" while checking: its config, and whether the fields degrees and
// revolutions depend on are sound (if not, unit conversions for it are not checked).
struct MotorEntry {
  MotorConfig config;
  bool scale_ok = true;
  bool number_ok = true;
  bool accel_ok = true;  // its default acceleration is what the file says
};

// A quantity as read: the value in the base unit and where its number is.
struct Quantity {
  double value = 0;
  const Value* node = nullptr;  // the number
  std::string path;             // of the number
  std::string written;          // "90 deg/s"
  bool base = true;             // given in the base unit
};

class Checker {
 public:
  Checker(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  Result<MotionFile, std::vector<FileError>> run() {
    auto doc = json::read(text_);
    if (!doc) {
      const json::Problem& p = doc.error();
      add(p.at, p.path, p.expected, p.found, p.message);
      return std::move(errors_);
    }
    for (const json::Problem& p : doc->duplicates) add(p.at, p.path, p.expected, p.found, p.message);
    file_data_.path = file_;
    top(doc->root);
    if (!errors_.empty()) {
      std::stable_sort(errors_.begin(), errors_.end(), [](const FileError& a, const FileError& b) {
        return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
      });
      return std::move(errors_);
    }
    return std::move(file_data_);
  }

 private:
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
    add(object.at, json::path_with_key(path, key), std::move(expected), "nothing", "missing " + quoted(key));
  }

  // Reports every key of `object` not in `keys`; true when there are none.
  bool known_keys(const Value& object, const std::string& path, Keys keys) {
    bool ok = true;
    for (const json::Member& m : object.members) {
      if (keys.contains(m.key)) continue;
      ok = false;
      const std::string expected = "one of " + keys.list();
      add(m.at, json::path_with_key(path, m.key), expected, found(m),
          "unknown key " + quoted(m.key) + "; expected " + expected + suggestion(m.key, keys));
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
  std::optional<double> number(const Value& v, const std::string& path, std::string_view what, double min,
                               double max, const std::string& unit) {
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

  // A quantity in the base unit. `steps_per_degree` is 0 when the motor's gearing is unknown or
  // broken: then degrees and revolutions are read but not converted (nothing is returned, and
  // nothing reported for it).
  std::optional<Quantity> quantity(const Value& v, const std::string& path, Dim dim, double steps_per_degree) {
    const DimInfo info = dim_info(dim);
    Quantity q;
    const Unit* unit = &info.units[0];
    if (v.is(Kind::kNumber)) {
      q.node = &v;
      q.path = path;
    } else if (v.is(Kind::kObject)) {
      if (!known_keys(v, path, info.keys)) return std::nullopt;
      if (v.members.empty()) {
        bad(v, path, info.expected, "a quantity needs a unit");
        return std::nullopt;
      }
      if (v.members.size() > 1) {
        const json::Member& extra = v.members[1];
        add(extra.at, json::path_with_key(path, extra.key), "one unit key", found(extra),
            "one unit only: " + quoted(extra.key) + " after " + quoted(v.members[0].key));
        return std::nullopt;
      }
      const json::Member& m = v.members[0];
      for (size_t i = 0; i < info.count; ++i) {
        if (info.units[i].key == m.key) unit = &info.units[i];
      }
      q.node = &m.value;
      q.path = json::path_with_key(path, m.key);
      if (!m.value.is(Kind::kNumber)) {
        wrong_type(m.value, q.path, std::string("a number of ") + unit->label);
        return std::nullopt;
      }
    } else {
      wrong_type(v, path, info.expected);
      return std::nullopt;
    }
    const double n = q.node->number;
    q.written = fmt(n) + " " + unit->label;
    q.base = unit->degrees == 0;
    if (q.base) {
      q.value = n;
    } else {
      if (steps_per_degree <= 0) return std::nullopt;
      q.value = n * unit->degrees * steps_per_degree;
      if (!std::isfinite(q.value)) {
        bad(*q.node, q.path, "a value that converts to a finite number of steps", q.written + " is too large");
        return std::nullopt;
      }
    }
    return q;
  }

  // "90 deg/s (800 steps/s)" or "800 steps/s".
  static std::string described(const Quantity& q, const char* base_unit) {
    return q.base ? q.written : q.written + " (" + fmt(q.value) + " " + base_unit + ")";
  }

  bool speed_ok(const Quantity& q) {
    const std::string expected = "a speed above 0 and at most " + fmt(kMaxRate) + " steps/s";
    if (q.value <= 0) {
      bad(*q.node, q.path, expected, "speed " + described(q, "steps/s") + " is not above 0");
      return false;
    }
    if (q.value > kMaxRate) {
      bad(*q.node, q.path, expected,
          "speed " + described(q, "steps/s") + " is faster than the board's " + fmt(kMaxRate) + " steps/s");
      return false;
    }
    if (q.value < kMinRate) {
      bad(*q.node, q.path, "a speed of at least one step per 89 s",
          "speed " + described(q, "steps/s") + " is slower than the board can time (one step per 89 s)");
      return false;
    }
    return true;
  }

  bool accel_ok(const Quantity& q) {
    if (q.value < 0 || q.value > kMaxAccel) {
      bad(*q.node, q.path, "an acceleration from 0 to " + fmt(kMaxAccel) + " steps/s²",
          "acceleration " + described(q, "steps/s²") + " is out of range");
      return false;
    }
    return true;
  }

  // A distance or position, within what one STM counts.
  bool steps_ok(const Quantity& q, double rounded) {
    if (std::fabs(rounded) > kMaxSteps) {
      bad(*q.node, q.path, "at most " + fmt(kMaxSteps) + " steps either way",
          described(q, "steps") + " is too far for the board to count");
      return false;
    }
    return true;
  }

  // ---- motor names

  const MotorEntry* find_motor(std::string_view name) const {
    for (const MotorEntry& e : motors_) {
      if (e.config.name == name) return &e;
    }
    return nullptr;
  }

  std::string declared_names() const {
    std::string out;
    for (const MotorEntry& e : motors_) out += (out.empty() ? "" : ", ") + shown(e.config.name);
    return out;
  }

  // A reference to a declared motor. With "motors" itself broken, names are not checked.
  const MotorEntry* motor_ref(const Value& v, const std::string& path, bool allow_all) {
    if (!v.is(Kind::kString)) {
      wrong_type(v, path, "a motor name (a string)");
      return nullptr;
    }
    const MotorEntry* e = find_motor(v.string);
    if (e == nullptr && motors_known_) {
      std::vector<std::string_view> names;
      for (const MotorEntry& m : motors_) names.push_back(m.config.name);
      std::string expected = motors_.empty() ? "a motor declared in \"motors\""
                                             : "a motor the file declares: " + declared_names();
      if (allow_all) expected += ", or \"all\"";
      bad(v, path, expected, "unknown motor " + quoted(v.string) + suggestion(v.string, names));
    }
    return e;
  }

  struct Names {
    std::vector<std::string> names;
    std::vector<const Value*> nodes;  // where each name is written ("all" for all of them)
    bool all = false;
  };

  // A motor name, a list of names, or "all" (every declared motor, in file order).
  std::optional<Names> motor_names(const Value& v, const std::string& path) {
    const size_t before = errors_.size();
    Names out;
    if (v.is(Kind::kString) && v.string == "all") {
      out.all = true;
      for (const MotorEntry& e : motors_) {
        out.names.push_back(e.config.name);
        out.nodes.push_back(&v);
      }
      return out;
    }
    if (v.is(Kind::kString)) {
      motor_ref(v, path, true);
      out.names.push_back(v.string);
      out.nodes.push_back(&v);
    } else if (v.is(Kind::kArray)) {
      if (v.items.empty()) bad(v, path, "a motor name, a list of names or \"all\"", "the list names no motor");
      std::set<std::string> seen;
      for (size_t i = 0; i < v.items.size(); ++i) {
        const Value& item = v.items[i];
        const std::string item_path = json::path_with_index(path, i);
        if (item.is(Kind::kString) && item.string == "all") {
          bad(item, item_path, "a motor name", "\"all\" stands alone, not in a list");
          continue;
        }
        if (motor_ref(item, item_path, false) == nullptr && !item.is(Kind::kString)) continue;
        if (!seen.insert(item.string).second) {
          bad(item, item_path, "each motor once", quoted(item.string) + " is listed twice");
          continue;
        }
        out.names.push_back(item.string);
        out.nodes.push_back(&item);
      }
    } else {
      wrong_type(v, path, "a motor name, a list of names or \"all\"");
    }
    if (errors_.size() != before) return std::nullopt;
    return out;
  }

  // ---- the top level

  void top(const Value& root) {
    const std::string path = "$";
    if (!root.is(Kind::kObject)) {
      bad(root, path, "an object with hmc_motion, motors and steps", "a motion file is a JSON object");
      return;
    }
    known_keys(root, path, kTopKeys);

    if (const Value* v = get(root, "hmc_motion")) {
      const std::string p = json::path_with_key(path, "hmc_motion");
      if (!v->is(Kind::kNumber)) {
        wrong_type(*v, p, "the format version 1");
      } else if (v->number != kFormatVersion) {
        bad(*v, p, "1", "format version " + fmt(v->number) + " is not one this reader knows");
      }
    } else {
      missing(root, path, "hmc_motion", "the format version 1");
    }

    if (const Value* v = get(root, "name")) {
      if (auto s = string(*v, json::path_with_key(path, "name"))) file_data_.name = *s;
    }

    if (const Value* v = get(root, "motors")) {
      motors(*v, json::path_with_key(path, "motors"));
    } else {
      missing(root, path, "motors", "an object of 1 to 3 motors");
    }

    if (const Value* v = get(root, "steps")) {
      const std::string p = json::path_with_key(path, "steps");
      if (!v->is(Kind::kArray)) {
        wrong_type(*v, p, "a list of steps");
      } else if (v->items.empty()) {
        bad(*v, p, "a list of at least one step", "a motion file needs at least one step");
      } else {
        const uint64_t total = steps(*v, p, 0, file_data_.steps);
        if (total > kMaxUnrolledSteps) {
          bad(*v, p, "at most " + fmt(kMaxUnrolledSteps) + " steps once repeats are unrolled",
              "the file unrolls to " + fmt(static_cast<double>(total)) + " steps");
        }
      }
    } else {
      missing(root, path, "steps", "a list of steps");
    }
  }

  // ---- motors

  void motors(const Value& v, const std::string& path) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object of 1 to 3 motors, by name");
      return;
    }
    motors_known_ = true;
    if (v.members.empty()) {
      bad(v, path, "1 to 3 motors", "a motion file declares at least one motor");
    } else if (v.members.size() > proto::kMotorCount) {
      bad(v, path, "1 to 3 motors", "the board has 3 steppers; " + std::to_string(v.members.size()) + " are declared");
    }
    std::map<uint32_t, std::string> numbers;
    for (const json::Member& m : v.members) {
      const std::string p = json::path_with_key(path, m.key);
      if (m.key.empty()) {
        add(m.at, p, "a name", found(m), "a motor needs a name");
      } else if (m.key == "all") {
        add(m.at, p, "another name", found(m), "the name \"all\" is reserved: it means every motor");
      }
      MotorEntry e = motor(m.value, p, m.key, numbers);
      e.config.name = m.key;
      motors_.push_back(e);
    }
    for (const MotorEntry& e : motors_) file_data_.motors.push_back(e.config);
  }

  MotorEntry motor(const Value& v, const std::string& path, const std::string& name,
                   std::map<uint32_t, std::string>& numbers) {
    MotorEntry e;
    MotorConfig& c = e.config;
    c.where = location(v.at, path);
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with motor, steps_per_rev, microstep, gear_ratio, speed, accel, limits");
      e.scale_ok = e.number_ok = false;
      return e;
    }
    known_keys(v, path, kMotorKeys);

    if (const Value* n = get(v, "motor")) {
      const std::string p = json::path_with_key(path, "motor");
      if (auto motor = integer(*n, p, "motor", 1, proto::kMotorCount)) {
        c.motor = *motor;
        if (const auto owner = numbers.find(*motor); owner != numbers.end()) {
          bad(*n, p, "each of the board's motors 1-3 once",
              "motor " + fmt(*motor) + " is already " + quoted(owner->second));
          e.number_ok = false;
        } else {
          numbers.emplace(*motor, name);
        }
      } else {
        e.number_ok = false;
      }
    } else {
      missing(v, path, "motor", "the board's motor 1, 2 or 3");
      e.number_ok = false;
    }
    if (!e.number_ok) c.motor = 0;

    if (const Value* n = get(v, "steps_per_rev")) {
      if (auto s = integer(*n, json::path_with_key(path, "steps_per_rev"), "steps_per_rev", 1, kMaxStepsPerRev)) {
        c.full_steps_per_rev = *s;
      } else {
        e.scale_ok = false;
      }
    }
    if (const Value* n = get(v, "microstep")) {
      const std::string p = json::path_with_key(path, "microstep");
      const std::string expected = "a power of two from 1 to 256";
      if (!n->is(Kind::kNumber)) {
        wrong_type(*n, p, expected);
        e.scale_ok = false;
      } else if (n->number != std::floor(n->number) || n->number < 1 || n->number > kMaxMicrostep ||
                 !proto::is_power_of_two(static_cast<uint32_t>(n->number))) {
        const bool in_range = n->number >= 1 && n->number <= kMaxMicrostep;
        bad(*n, p, expected, "microstep " + fmt(n->number) + (in_range ? " is not a power of two" : " is out of range"));
        e.scale_ok = false;
      } else {
        c.microstep = static_cast<uint32_t>(n->number);
      }
    }
    if (const Value* n = get(v, "gear_ratio")) {
      const std::string p = json::path_with_key(path, "gear_ratio");
      if (!n->is(Kind::kNumber)) {
        wrong_type(*n, p, "a number above 0 (motor turns per output turn)");
        e.scale_ok = false;
      } else if (n->number <= 0) {
        bad(*n, p, "a number above 0 (motor turns per output turn)", "gear_ratio " + fmt(n->number) + " is not above 0");
        e.scale_ok = false;
      } else {
        c.gear_ratio = n->number;
        // Degrees must convert to a finite number of steps above 0 (a ratio of 1e-320 would not).
        const double spd = c.steps_per_degree();
        if (e.scale_ok && !(spd > 0 && std::isfinite(spd))) {
          bad(*n, p, "a gear ratio with which a degree is a finite number of steps above 0",
              "gear_ratio " + fmt(n->number) + " is out of range");
          e.scale_ok = false;
          c.gear_ratio = 1;
        }
      }
    }
    const double scale = e.scale_ok ? c.steps_per_degree() : 0;  // 0: unknown

    if (const Value* n = get(v, "speed")) {
      if (auto q = quantity(*n, json::path_with_key(path, "speed"), Dim::kSpeed, scale); q && speed_ok(*q)) {
        c.speed = q->value;
      }
    }
    if (const Value* n = get(v, "accel")) {
      e.accel_ok = false;
      if (auto q = quantity(*n, json::path_with_key(path, "accel"), Dim::kAccel, scale); q && accel_ok(*q)) {
        c.accel = q->value;
        e.accel_ok = true;
      }
    }
    if (const Value* n = get(v, "limits")) limits(*n, json::path_with_key(path, "limits"), scale, c);
    return e;
  }

  void limits(const Value& v, const std::string& path, double scale, MotorConfig& c) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with min and/or max");
      return;
    }
    known_keys(v, path, kLimitKeys);
    std::optional<Quantity> min;
    std::optional<Quantity> max;
    if (const Value* n = get(v, "min")) {
      min = quantity(*n, json::path_with_key(path, "min"), Dim::kDistance, scale);
      if (min && !steps_ok(*min, min->value)) min.reset();
    }
    if (const Value* n = get(v, "max")) {
      max = quantity(*n, json::path_with_key(path, "max"), Dim::kDistance, scale);
      if (max && !steps_ok(*max, max->value)) max.reset();
    }
    if (min && max && !(min->value < max->value)) {
      bad(*max->node, max->path, "a max above min (" + described(*min, "steps") + ")",
          "max " + described(*max, "steps") + " is not above min " + described(*min, "steps"));
      return;
    }
    if (min) c.min_position = min->value;
    if (max) c.max_position = max->value;
  }

  // ---- steps

  // Checks a list of steps into `out`; returns how many steps they unroll to.
  uint64_t steps(const Value& list, const std::string& path, int repeat_depth, std::vector<Step>& out) {
    uint64_t total = 0;
    for (size_t i = 0; i < list.items.size(); ++i) {
      total += step(list.items[i], json::path_with_index(path, i), repeat_depth, out);
    }
    return total;
  }

  // One step; returns its unrolled size (0 when it yields no step).
  uint64_t step(const Value& v, const std::string& path, int repeat_depth, std::vector<Step>& out) {
    const std::string shape = "a step: an object with one of " + Keys(kActions).list() + ", and an optional label";
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, shape);
      return 0;
    }
    const size_t before = errors_.size();
    const bool keys_ok = known_keys(v, path, kStepKeys);
    const json::Member* action = nullptr;
    for (const json::Member& m : v.members) {
      if (!Keys(kActions).contains(m.key)) continue;
      if (action == nullptr) {
        action = &m;
      } else {
        add(m.at, json::path_with_key(path, m.key), "one action per step", found(m),
            "a step has one action: " + quoted(m.key) + " comes after " + quoted(action->key));
      }
    }
    if (action == nullptr) {
      if (keys_ok) bad(v, path, "one of " + Keys(kActions).list(), "a step needs an action");
      return 0;
    }

    Step s;
    s.where = location(v.at, path);
    if (const Value* label = get(v, "label")) {
      if (auto text = string(*label, json::path_with_key(path, "label"))) s.label = *text;
    }
    const Value& a = action->value;
    const std::string p = json::path_with_key(path, action->key);
    uint64_t size = 1;
    bool ok = false;
    if (action->key == "home") {
      ok = home(a, p, s);
    } else if (action->key == "move") {
      ok = move_step(a, p, s);
    } else if (action->key == "together") {
      ok = together(a, p, s);
    } else if (action->key == "servo") {
      ok = servo(a, p, s);
    } else if (action->key == "led") {
      ok = led(a, p, s);
    } else if (action->key == "wait") {
      ok = wait(a, p, s);
    } else if (action->key == "repeat") {
      size = repeat(a, p, repeat_depth, s);
      ok = size > 0;
    } else {  // stop
      ok = stop(a, p, s);
    }
    if (!ok || errors_.size() != before) return 0;
    out.push_back(std::move(s));
    return size;
  }

  bool home(const Value& v, const std::string& path, Step& s) {
    auto names = motor_names(v, path);
    if (!names) return false;
    bool ok = true;
    for (size_t i = 0; i < names->names.size(); ++i) {
      const MotorEntry* e = find_motor(names->names[i]);
      if (e == nullptr || e->config.motor == 0 || proto::motor_has_switches(e->config.motor)) continue;
      bad(*names->nodes[i], path, "motors with limit switches (the board's motors 1 and 2)",
          quoted(names->names[i]) + " is the board's motor " + fmt(e->config.motor) +
              ", which has no limit switches to home against");
      ok = false;
    }
    s.action = HomeStep{std::move(names->names)};
    return ok;
  }

  bool stop(const Value& v, const std::string& path, Step& s) {
    auto names = motor_names(v, path);
    if (!names) return false;
    StopStep stop;
    if (!names->all) stop.motors = std::move(names->names);
    s.action = std::move(stop);
    return true;
  }

  bool move_step(const Value& v, const std::string& path, Step& s) {
    bool wait = true;
    auto m = move(v, path, false, wait);
    if (!m) return false;
    s.action = MoveStep{std::move(*m), wait};
    return true;
  }

  bool together(const Value& v, const std::string& path, Step& s) {
    if (!v.is(Kind::kArray) || v.items.size() < 2) {
      if (v.is(Kind::kArray)) {
        bad(v, path, "a list of at least 2 moves", "a together step moves at least 2 motors");
      } else {
        wrong_type(v, path, "a list of at least 2 moves");
      }
      return false;
    }
    const size_t before = errors_.size();
    TogetherStep t;
    std::set<std::string> moving;
    for (size_t i = 0; i < v.items.size(); ++i) {
      const Value& item = v.items[i];
      const std::string p = json::path_with_index(path, i);
      bool unused = true;
      auto m = move(item, p, true, unused);
      if (!item.is(Kind::kObject)) continue;
      const Value* name = get(item, "motor");
      if (name != nullptr && name->is(Kind::kString) && find_motor(name->string) != nullptr &&
          !moving.insert(name->string).second) {
        bad(*name, json::path_with_key(p, "motor"), "each motor once in a together step",
            quoted(name->string) + " already moves in this step");
      }
      if (m) t.moves.push_back(std::move(*m));
    }
    if (errors_.size() != before) return false;
    s.action = std::move(t);
    return true;
  }

  std::optional<Move> move(const Value& v, const std::string& path, bool in_together, bool& wait) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "a move: an object with motor and by or to");
      return std::nullopt;
    }
    const size_t before = errors_.size();
    known_keys(v, path, in_together ? Keys(kTogetherMoveKeys) : Keys(kMoveKeys));
    Move m;
    m.where = location(v.at, path);

    const MotorEntry* e = nullptr;
    if (const Value* n = get(v, "motor")) {
      e = motor_ref(*n, json::path_with_key(path, "motor"), false);
      if (n->is(Kind::kString)) m.motor = n->string;
    } else {
      missing(v, path, "motor", "a motor name");
    }
    const double scale = e != nullptr && e->scale_ok ? e->config.steps_per_degree() : 0;  // 0: unknown

    // Where to: exactly one of by and to.
    const json::Member* by = v.find("by");
    const json::Member* to = v.find("to");
    if (by != nullptr && to != nullptr) {
      const json::Member& later = by->at.offset > to->at.offset ? *by : *to;
      const json::Member& earlier = &later == by ? *to : *by;
      add(later.at, json::path_with_key(path, later.key), "either 'by' or 'to'", found(later),
          "a move has either 'by' (relative) or 'to' (absolute), not both: " + quoted(later.key) + " after " +
              quoted(earlier.key));
    } else if (by != nullptr) {
      const std::string p = json::path_with_key(path, "by");
      if (auto q = quantity(by->value, p, Dim::kDistance, scale)) {
        const double steps = std::round(q->value) + 0.0;
        if (steps == 0) {
          bad(*q->node, q->path, "a distance of at least one whole step", described(*q, "steps") + " moves 0 steps");
        } else if (steps_ok(*q, steps)) {
          m.distance = steps;
        }
      }
    } else if (to != nullptr) {
      const std::string p = json::path_with_key(path, "to");
      m.absolute = true;
      if (auto q = quantity(to->value, p, Dim::kDistance, scale)) {
        const double steps = std::round(q->value) + 0.0;  // + 0.0: no -0
        if (steps_ok(*q, steps)) {
          m.distance = steps;
          const MotorConfig* c = e != nullptr ? &e->config : nullptr;
          const bool below = c != nullptr && c->min_position && steps < *c->min_position;
          const bool above = c != nullptr && c->max_position && steps > *c->max_position;
          if (below || above) {
            std::string range = "a position within " + shown(m.motor) + "'s limits: ";
            if (c->min_position && c->max_position) {
              range += "from " + fmt(*c->min_position) + " to " + fmt(*c->max_position) + " steps";
            } else if (c->min_position) {
              range += "at least " + fmt(*c->min_position) + " steps";
            } else {
              range += "at most " + fmt(*c->max_position) + " steps";
            }
            bad(*q->node, q->path, range,
                "position " + described(*q, "steps") + " is " + (below ? "below" : "above") + " " + shown(m.motor) + "'s " +
                    (below ? "min" : "max") + " limit " +
                    fmt(below ? *c->min_position : *c->max_position) + " steps");
          }
        }
      }
    } else {
      add(v.at, json::path_with_key(path, "by"), "'by' (a relative distance) or 'to' (a position)", "nothing",
          "a move needs 'by' or 'to'");
    }

    // The profile: the move's own speed and acceleration, else the motor's.
    Profile& prof = m.profile;
    prof.speed = e != nullptr ? e->config.speed : 0;
    prof.accel = e != nullptr ? e->config.accel : 0;
    if (const Value* n = get(v, "speed")) {
      if (auto q = quantity(*n, json::path_with_key(path, "speed"), Dim::kSpeed, scale); q && speed_ok(*q)) {
        prof.speed = q->value;
      }
    }
    // Whether prof.accel is what the file means (not a default standing in for a broken value).
    bool accel_known = e != nullptr && e->accel_ok;
    if (const Value* n = get(v, "accel")) {
      accel_known = false;
      if (auto q = quantity(*n, json::path_with_key(path, "accel"), Dim::kAccel, scale); q && accel_ok(*q)) {
        prof.accel = q->value;
        accel_known = true;
      }
    }
    const Value* profile = get(v, "profile");
    bool kind_known = true;
    prof.kind = prof.accel > 0 ? ProfileKind::kTrapezoid : ProfileKind::kConstant;
    if (profile != nullptr) {
      const std::string p = json::path_with_key(path, "profile");
      const std::string expected = "one of " + Keys(kProfiles).list();
      kind_known = false;
      if (!profile->is(Kind::kString)) {
        wrong_type(*profile, p, expected);
      } else {
        for (size_t i = 0; i < std::size(kProfiles); ++i) {
          if (profile->string == kProfiles[i]) {
            prof.kind = kProfileKinds[i];
            kind_known = true;
          }
        }
        if (!kind_known) {
          bad(*profile, p, expected, "unknown profile " + quoted(profile->string) + suggestion(profile->string, kProfiles));
        } else if ((prof.kind == ProfileKind::kTrapezoid || prof.kind == ProfileKind::kSCurve) && prof.accel <= 0 &&
                   accel_known) {
          bad(*profile, p, "an acceleration above 0, in the move's 'accel' or its motor's",
              "the " + profile->string + " profile needs an acceleration above 0");
        }
      }
    }
    if (const Value* n = get(v, "stages")) {
      const std::string p = json::path_with_key(path, "stages");
      if (kind_known && prof.kind != ProfileKind::kStaged) {
        bad(*n, p, "'stages' only with \"profile\": \"staged\"", "'stages' applies to the staged profile only");
      } else if (auto k = integer(*n, p, "stages", kMinStages, kMaxStages)) {
        prof.stages = *k;
      }
    }
    if (const Value* n = get(v, "jerk")) {
      const std::string p = json::path_with_key(path, "jerk");
      if (kind_known && prof.kind != ProfileKind::kSCurve) {
        bad(*n, p, "'jerk' only with \"profile\": \"s-curve\"", "'jerk' applies to the s-curve profile only");
      } else if (auto q = quantity(*n, p, Dim::kJerk, scale)) {
        if (q->value <= 0) {
          bad(*q->node, q->path, "a jerk above 0", "jerk " + described(*q, "steps/s³") + " is not above 0");
        } else {
          prof.jerk = q->value;
        }
      }
    } else if (prof.kind == ProfileKind::kSCurve) {
      prof.jerk = prof.accel * kJerkPerAccel;
    }
    if (const Value* n = get(v, "wait")) {  // only reached for move steps: together refuses the key
      if (!n->is(Kind::kBool)) {
        wrong_type(*n, json::path_with_key(path, "wait"), "true or false");
      } else {
        wait = n->boolean;
      }
    }
    if (errors_.size() != before || e == nullptr) return std::nullopt;
    return m;
  }

  bool servo(const Value& v, const std::string& path, Step& s) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with id and angle");
      return false;
    }
    const size_t before = errors_.size();
    known_keys(v, path, kServoKeys);
    ServoStep out;
    if (const Value* n = get(v, "id")) {
      if (auto id = integer(*n, json::path_with_key(path, "id"), "servo", 1, proto::kServoCount)) out.servo = *id;
    } else {
      missing(v, path, "id", "servo 1 or 2");
    }
    if (const Value* n = get(v, "angle")) {
      if (auto a = number(*n, json::path_with_key(path, "angle"), "angle", kMinServoAngle, kMaxServoAngle, " degrees")) {
        out.angle = *a;
      }
    } else {
      missing(v, path, "angle", "an angle in degrees");
    }
    if (errors_.size() != before) return false;
    s.action = out;
    return true;
  }

  std::optional<Colour> colour(const Value& v, const std::string& path) {
    const std::string expected = "\"#RRGGBB\", \"#RRGGBBWW\", [r, g, b], [r, g, b, w] or \"off\"";
    if (v.is(Kind::kString)) {
      if (v.string == "off") return Colour{};
      const std::string& t = v.string;
      const bool shape = (t.size() == 7 || t.size() == 9) && t[0] == '#' &&
                         std::all_of(t.begin() + 1, t.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; });
      if (!shape) {
        bad(v, path, expected, "a colour is \"#\" and 6 or 8 hex digits, or \"off\"");
        return std::nullopt;
      }
      const auto digit = [](char c) {
        return static_cast<uint32_t>(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10);
      };
      const auto byte = [&](size_t i) { return digit(t[i]) * 16 + digit(t[i + 1]); };
      return Colour{byte(1), byte(3), byte(5), t.size() == 9 ? byte(7) : 0};
    }
    if (v.is(Kind::kArray)) {
      if (v.items.size() != 3 && v.items.size() != 4) {
        bad(v, path, expected, "a colour list has 3 or 4 values (r, g, b and optionally w)");
        return std::nullopt;
      }
      static constexpr const char* kChannels[] = {"red", "green", "blue", "white"};
      uint32_t c[4] = {0, 0, 0, 0};
      bool ok = true;
      for (size_t i = 0; i < v.items.size(); ++i) {
        if (auto x = integer(v.items[i], json::path_with_index(path, i), kChannels[i], 0, 255)) {
          c[i] = *x;
        } else {
          ok = false;
        }
      }
      if (!ok) return std::nullopt;
      return Colour{c[0], c[1], c[2], c[3]};
    }
    wrong_type(v, path, expected);
    return std::nullopt;
  }

  bool led(const Value& v, const std::string& path, Step& s) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with strip and colour");
      return false;
    }
    const size_t before = errors_.size();
    known_keys(v, path, kLedKeys);
    LedStep out;
    if (const Value* n = get(v, "strip")) {
      if (auto strip = integer(*n, json::path_with_key(path, "strip"), "strip", 1, proto::kStripCount)) out.strip = *strip;
    } else {
      missing(v, path, "strip", "strip 1 or 2");
    }
    if (const Value* n = get(v, "colour")) {
      if (auto c = colour(*n, json::path_with_key(path, "colour"))) out.colour = *c;
    } else {
      missing(v, path, "colour", "a colour");
    }
    if (const Value* n = get(v, "from")) {
      if (auto c = colour(*n, json::path_with_key(path, "from"))) out.from = *c;
    }
    if (const Value* n = get(v, "fade_ms")) {
      if (auto ms = number(*n, json::path_with_key(path, "fade_ms"), "fade_ms", 0, kMaxFadeMs, " ms")) out.fade_ms = *ms;
    }
    if (errors_.size() != before) return false;
    s.action = out;
    return true;
  }

  bool wait(const Value& v, const std::string& path, Step& s) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with ms or until_done");
      return false;
    }
    const size_t before = errors_.size();
    known_keys(v, path, kWaitKeys);
    const json::Member* ms = v.find("ms");
    const json::Member* until = v.find("until_done");
    WaitStep out;
    if (ms != nullptr && until != nullptr) {
      const json::Member& later = ms->at.offset > until->at.offset ? *ms : *until;
      add(later.at, json::path_with_key(path, later.key), "either 'ms' or 'until_done'", found(later),
          "a wait has either 'ms' or 'until_done', not both");
    } else if (ms != nullptr) {
      if (auto n = number(ms->value, json::path_with_key(path, "ms"), "ms", 0, kMaxWaitMs, " ms")) out.ms = *n;
    } else if (until != nullptr) {
      if (auto names = motor_names(until->value, json::path_with_key(path, "until_done"))) {
        out.until_done = std::move(names->names);
      }
    } else if (errors_.size() == before) {
      add(v.at, json::path_with_key(path, "ms"), "'ms' (a pause) or 'until_done' (motor names)", "nothing",
          "a wait needs 'ms' or 'until_done'");
    }
    if (errors_.size() != before) return false;
    s.action = std::move(out);
    return true;
  }

  // Returns the repeat's unrolled size, 0 when it is broken.
  uint64_t repeat(const Value& v, const std::string& path, int repeat_depth, Step& s) {
    if (!v.is(Kind::kObject)) {
      wrong_type(v, path, "an object with count and steps");
      return 0;
    }
    if (repeat_depth >= kMaxRepeatDepth) {
      bad(v, path, "at most " + std::to_string(kMaxRepeatDepth) + " repeats inside one another",
          "repeats nest more than " + std::to_string(kMaxRepeatDepth) + " deep");
      return 0;
    }
    const size_t before = errors_.size();
    known_keys(v, path, kRepeatKeys);
    RepeatStep out;
    if (const Value* n = get(v, "count")) {
      if (auto c = integer(*n, json::path_with_key(path, "count"), "count", 1, kMaxRepeatCount)) out.count = *c;
    } else {
      missing(v, path, "count", "a count from 1 to " + fmt(kMaxRepeatCount));
    }
    uint64_t inner = 0;
    if (const Value* n = get(v, "steps")) {
      const std::string p = json::path_with_key(path, "steps");
      if (!n->is(Kind::kArray)) {
        wrong_type(*n, p, "a list of steps");
      } else if (n->items.empty()) {
        bad(*n, p, "a list of at least one step", "a repeat needs at least one step");
      } else {
        inner = steps(*n, p, repeat_depth + 1, out.steps);
      }
    } else {
      missing(v, path, "steps", "a list of steps");
    }
    if (errors_.size() != before) return 0;
    const uint64_t size = inner * out.count;
    if (size > kMaxUnrolledSteps) {
      bad(v, path, "at most " + fmt(kMaxUnrolledSteps) + " steps once repeats are unrolled",
          "this repeat unrolls to " + fmt(static_cast<double>(size)) + " steps");
      return 0;
    }
    s.action = std::move(out);
    return size;
  }

  std::string_view text_;
  const std::string& file_;
  std::vector<FileError> errors_;
  MotionFile file_data_;
  std::vector<MotorEntry> motors_;
  bool motors_known_ = false;  // "motors" is an object: names can be checked against it
};

}  // namespace

std::string FileError::text() const {
  std::string out = where.file;
  if (where.line > 0) out += ":" + std::to_string(where.line) + ":" + std::to_string(where.column);
  out += ": ";
  if (!where.path.empty()) out += where.path + ": ";
  out += message;
  // What the message already says is not repeated.
  std::string detail;
  if (!expected.empty() && message.find("expected " + expected) == std::string::npos) detail = "expected " + expected;
  if (!found.empty()) detail += (detail.empty() ? "" : ", ") + std::string("found ") + found;
  if (!detail.empty()) out += " (" + detail + ")";
  return out;
}

const MotorConfig* MotionFile::motor(const std::string& motor_name) const {
  for (const MotorConfig& m : motors) {
    if (m.name == motor_name) return &m;
  }
  return nullptr;
}

Result<MotionFile, std::vector<FileError>> parse_motion_file(const std::string& text, const std::string& path) {
  return Checker(text, path).run();
}

Result<MotionFile, std::vector<FileError>> load_motion_file(const std::string& path) {
  const auto unreadable = [&](int error) {
    FileError e;
    e.where.file = path;
    e.message = "cannot read the file: " + std::error_code(error, std::generic_category()).message();
    return std::vector<FileError>{e};
  };
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return unreadable(errno);
  std::string text;
  char buf[65536];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  const int error = errno;
  std::fclose(f);
  if (failed) return unreadable(error);
  return parse_motion_file(text, path);
}

}  // namespace hmc::motion
