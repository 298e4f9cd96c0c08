// Motion files: the "motors" (MotorTable, motion_file_check.h) — each motor's number, gearing,
// default speed and acceleration and soft limits, and the motor names that steps use.
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "motion_file_check.h"

namespace hmc::motion::reading {

void MotorTable::read(const Value& v, const std::string& path, std::vector<MotorConfig>& out) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object of 1 to 3 motors, by name");
    return;
  }
  motors_known_ = true;
  if (v.members.empty()) {
    r_.bad(v, path, "1 to 3 motors", "a motion file declares at least one motor");
  } else if (v.members.size() > proto::kMotorCount) {
    r_.bad(v, path, "1 to 3 motors", "the board has 3 steppers; " + std::to_string(v.members.size()) + " are declared");
  }
  std::map<uint32_t, std::string> numbers;
  for (const json::Member& m : v.members) {
    const std::string p = json::path_with_key(path, m.key);
    if (m.key.empty()) {
      r_.add(m.at, p, "a name", r_.found(m), "a motor needs a name");
    } else if (m.key == "all") {
      r_.add(m.at, p, "another name", r_.found(m), "the name \"all\" is reserved: it means every motor");
    }
    MotorEntry e = motor(m.value, p, m.key, numbers);
    e.config.name = m.key;
    motors_.push_back(e);
  }
  for (const MotorEntry& e : motors_) out.push_back(e.config);
}

MotorEntry MotorTable::motor(const Value& v, const std::string& path, const std::string& name,
                             std::map<uint32_t, std::string>& numbers) {
  MotorEntry e;
  MotorConfig& c = e.config;
  c.where = r_.location(v.at, path);
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with motor, steps_per_rev, microstep, gear_ratio, speed, accel, limits");
    e.scale_ok = e.number_ok = false;
    return e;
  }
  r_.known_keys(v, path, kMotorKeys);

  if (const Value* n = r_.get(v, "motor")) {
    const std::string p = json::path_with_key(path, "motor");
    if (auto motor = r_.integer(*n, p, "motor", 1, proto::kMotorCount)) {
      c.motor = *motor;
      if (const auto owner = numbers.find(*motor); owner != numbers.end()) {
        r_.bad(*n, p, "each of the board's motors 1-3 once",
               "motor " + fmt(*motor) + " is already " + single_quoted(owner->second));
        e.number_ok = false;
      } else {
        numbers.emplace(*motor, name);
      }
    } else {
      e.number_ok = false;
    }
  } else {
    r_.missing(v, path, "motor", "the board's motor 1, 2 or 3");
    e.number_ok = false;
  }
  if (!e.number_ok) c.motor = 0;

  if (const Value* n = r_.get(v, "steps_per_rev")) {
    if (auto s = r_.integer(*n, json::path_with_key(path, "steps_per_rev"), "steps_per_rev", 1, kMaxStepsPerRev)) {
      c.full_steps_per_rev = *s;
    } else {
      e.scale_ok = false;
    }
  }
  if (const Value* n = r_.get(v, "microstep")) {
    const std::string p = json::path_with_key(path, "microstep");
    const std::string expected = "a power of two from 1 to 256";
    if (!n->is(Kind::kNumber)) {
      r_.wrong_type(*n, p, expected);
      e.scale_ok = false;
    } else if (n->number != std::floor(n->number) || n->number < 1 || n->number > kMaxMicrostep ||
               !proto::is_power_of_two(static_cast<uint32_t>(n->number))) {
      const bool in_range = n->number >= 1 && n->number <= kMaxMicrostep;
      r_.bad(*n, p, expected,
             "microstep " + fmt(n->number) + (in_range ? " is not a power of two" : " is out of range"));
      e.scale_ok = false;
    } else {
      c.microstep = static_cast<uint32_t>(n->number);
    }
  }
  if (const Value* n = r_.get(v, "gear_ratio")) {
    const std::string p = json::path_with_key(path, "gear_ratio");
    if (!n->is(Kind::kNumber)) {
      r_.wrong_type(*n, p, "a number above 0 (motor turns per output turn)");
      e.scale_ok = false;
    } else if (n->number <= 0) {
      r_.bad(*n, p, "a number above 0 (motor turns per output turn)",
             "gear_ratio " + fmt(n->number) + " is not above 0");
      e.scale_ok = false;
    } else {
      c.gear_ratio = n->number;
      // Degrees must convert to a finite number of steps above 0 (a ratio of 1e-320 would not).
      const double spd = c.steps_per_degree();
      if (e.scale_ok && !(spd > 0 && std::isfinite(spd))) {
        r_.bad(*n, p, "a gear ratio with which a degree is a finite number of steps above 0",
               "gear_ratio " + fmt(n->number) + " is out of range");
        e.scale_ok = false;
        c.gear_ratio = 1;
      }
    }
  }
  const Scale scale = e.scale();

  if (const Value* n = r_.get(v, "speed")) {
    if (auto q = q_.quantity(*n, json::path_with_key(path, "speed"), Dim::kSpeed, scale); q && q_.speed_ok(*q)) {
      c.speed = q->value;
    }
  }
  if (const Value* n = r_.get(v, "accel")) {
    e.accel_ok = false;
    if (auto q = q_.quantity(*n, json::path_with_key(path, "accel"), Dim::kAccel, scale); q && q_.accel_ok(*q)) {
      c.accel = q->value;
      e.accel_ok = true;
    }
  }
  if (const Value* n = r_.get(v, "limits")) limits(*n, json::path_with_key(path, "limits"), scale, c);
  return e;
}

void MotorTable::limits(const Value& v, const std::string& path, const Scale& scale, MotorConfig& c) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with min and/or max");
    return;
  }
  r_.known_keys(v, path, kLimitKeys);
  std::optional<Quantity> min;
  std::optional<Quantity> max;
  if (const Value* n = r_.get(v, "min")) {
    min = q_.quantity(*n, json::path_with_key(path, "min"), Dim::kDistance, scale);
    if (min && !q_.steps_ok(*min, min->value)) min.reset();
  }
  if (const Value* n = r_.get(v, "max")) {
    max = q_.quantity(*n, json::path_with_key(path, "max"), Dim::kDistance, scale);
    if (max && !q_.steps_ok(*max, max->value)) max.reset();
  }
  if (min && max && !(min->value < max->value)) {
    r_.bad(*max->node, max->path, "a max above min (" + q_.described(*min, "steps") + ")",
           "max " + q_.described(*max, "steps") + " is not above min " + q_.described(*min, "steps"));
    return;
  }
  if (min) c.min_position = min->value;
  if (max) c.max_position = max->value;
}

const MotorEntry* MotorTable::find_motor(std::string_view name) const {
  for (const MotorEntry& e : motors_) {
    if (e.config.name == name) return &e;
  }
  return nullptr;
}

std::string MotorTable::declared_names() const {
  std::string out;
  for (const MotorEntry& e : motors_) out += (out.empty() ? "" : ", ") + shown(e.config.name);
  return out;
}

// A reference to a declared motor. With "motors" itself broken, names are not checked.
const MotorEntry* MotorTable::motor_ref(const Value& v, const std::string& path, bool allow_all) {
  if (!v.is(Kind::kString)) {
    r_.wrong_type(v, path, "a motor name (a string)");
    return nullptr;
  }
  const MotorEntry* e = find_motor(v.string);
  if (e == nullptr && motors_known_) {
    std::vector<std::string_view> names;
    for (const MotorEntry& m : motors_) names.push_back(m.config.name);
    std::string expected =
        motors_.empty() ? "a motor declared in \"motors\"" : "a motor the file declares: " + declared_names();
    if (allow_all) expected += ", or \"all\"";
    r_.bad(v, path, expected, "unknown motor " + single_quoted(v.string) + suggestion(v.string, names));
  }
  return e;
}

// A motor name, a list of names, or "all" (every declared motor, in file order).
std::optional<MotorTable::Names> MotorTable::motor_names(const Value& v, const std::string& path) {
  const size_t before = r_.count();
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
    if (v.items.empty()) r_.bad(v, path, "a motor name, a list of names or \"all\"", "the list names no motor");
    std::set<std::string> seen;
    for (size_t i = 0; i < v.items.size(); ++i) {
      const Value& item = v.items[i];
      const std::string item_path = json::path_with_index(path, i);
      if (item.is(Kind::kString) && item.string == "all") {
        r_.bad(item, item_path, "a motor name", "\"all\" stands alone, not in a list");
        continue;
      }
      if (motor_ref(item, item_path, false) == nullptr && !item.is(Kind::kString)) continue;
      if (!seen.insert(item.string).second) {
        r_.bad(item, item_path, "each motor once", single_quoted(item.string) + " is listed twice");
        continue;
      }
      out.names.push_back(item.string);
      out.nodes.push_back(&item);
    }
  } else {
    r_.wrong_type(v, path, "a motor name, a list of names or \"all\"");
  }
  if (r_.count() != before) return std::nullopt;
  return out;
}

void MotorTable::from_profile(const hmc::Profile& profile, const Location& where, std::vector<MotorConfig>& out) {
  motors_known_ = true;
  for (const hmc::Axis& axis : profile.axes) {
    MotorEntry e;
    MotorConfig& c = e.config;
    c.name = axis.name;
    c.motor = axis.motor;
    c.full_steps_per_rev = axis.steps_per_rev;
    c.microstep = axis.microstep;
    c.gear_ratio = axis.gear_ratio;
    c.axis = axis;
    c.where = where;
    const double per_unit = axis.steps_per_unit();  // per mm or per degree
    if (!axis.rotary) e.steps_per_mm = per_unit;
    e.sign = axis.invert ? -1 : 1;
    // The profile checks its own values; the board's ranges in steps are checked here.
    const std::string unit = axis.rotary ? " deg" : " mm";
    if (axis.speed) {
      c.speed = *axis.speed * per_unit;
      if (!(c.speed >= kMinRate && c.speed <= kMaxRate)) {
        r_.errors().push_back(FileError{where, "a speed from one step per 89 s to " + fmt(kMaxRate) + " steps/s",
                                        fmt(*axis.speed) + unit + "/s",
                                        "axis " + single_quoted(axis.name) + "'s speed " + fmt(*axis.speed) + unit +
                                            "/s is " + fmt(c.speed) + " steps/s, beyond what the board can time"});
        c.speed = std::clamp(c.speed, kMinRate, kMaxRate);
      }
    }
    if (axis.accel) {
      c.accel = *axis.accel * per_unit;
      if (!(c.accel >= 0 && c.accel <= kMaxAccel)) {
        r_.errors().push_back(FileError{where, "an acceleration from 0 to " + fmt(kMaxAccel) + " steps/s²",
                                        fmt(*axis.accel) + unit + "/s²",
                                        "axis " + single_quoted(axis.name) + "'s acceleration " + fmt(*axis.accel) +
                                            unit + "/s² is " + fmt(c.accel) + " steps/s², out of the board's range"});
        c.accel = std::clamp(c.accel, 0.0, kMaxAccel);
      }
    }
    // The limits in the axis's sense, as the motor counts: an inverted axis swaps them.
    if (axis.limit_min) (axis.invert ? c.max_position : c.min_position) = *axis.limit_min * per_unit * e.sign;
    if (axis.limit_max) (axis.invert ? c.min_position : c.max_position) = *axis.limit_max * per_unit * e.sign;
    motors_.push_back(e);
  }
  for (const MotorEntry& e : motors_) out.push_back(e.config);
}

}  // namespace hmc::motion::reading
