// Motion files: unit conversion (QuantityReader, motion_file_check.h). A quantity is a plain
// number in the base unit (steps, steps/s, steps/s², steps/s³) or an object naming one unit;
// degrees and revolutions are of the motor's output, through its gearing; millimetres are of a
// linear axis of the machine profile the file names (docs/config.md), through its drive.
#include <cmath>
#include <string>

#include "motion_file_check.h"

namespace hmc::motion::reading {
namespace {

// A unit is the base unit, or so many output degrees, or so many millimetres of a linear axis.
enum class Through : uint8_t { kBase, kDegrees, kMillimetres };
struct Unit {
  std::string_view key;
  Through through;
  double factor;  // degrees or millimetres per unit
  const char* label;
};
constexpr Unit kDistanceUnits[] = {
    {"steps", Through::kBase, 1, "steps"}, {"deg", Through::kDegrees, 1, "deg"}, {"rev", Through::kDegrees, 360, "rev"}};
constexpr Unit kSpeedUnits[] = {{"steps_per_s", Through::kBase, 1, "steps/s"},
                                {"deg_per_s", Through::kDegrees, 1, "deg/s"},
                                {"rpm", Through::kDegrees, 6, "rpm"}};
constexpr Unit kAccelUnits[] = {{"steps_per_s2", Through::kBase, 1, "steps/s²"},
                                {"deg_per_s2", Through::kDegrees, 1, "deg/s²"}};
constexpr Unit kJerkUnits[] = {{"steps_per_s3", Through::kBase, 1, "steps/s³"},
                               {"deg_per_s3", Through::kDegrees, 1, "deg/s³"}};
// A linear axis of a profile: millimetres where the others have degrees (as `hmc move` takes them).
constexpr Unit kLinearDistanceUnits[] = {{"steps", Through::kBase, 1, "steps"},
                                         {"mm", Through::kMillimetres, 1, "mm"},
                                         {"rev", Through::kDegrees, 360, "rev"}};
constexpr Unit kLinearSpeedUnits[] = {{"steps_per_s", Through::kBase, 1, "steps/s"},
                                      {"mm_per_s", Through::kMillimetres, 1, "mm/s"},
                                      {"rpm", Through::kDegrees, 6, "rpm"}};
constexpr Unit kLinearAccelUnits[] = {{"steps_per_s2", Through::kBase, 1, "steps/s²"},
                                      {"mm_per_s2", Through::kMillimetres, 1, "mm/s²"}};
constexpr Unit kLinearJerkUnits[] = {{"steps_per_s3", Through::kBase, 1, "steps/s³"},
                                     {"mm_per_s3", Through::kMillimetres, 1, "mm/s³"}};
constexpr std::string_view kDistanceKeys[] = {"steps", "deg", "rev"};
constexpr std::string_view kSpeedKeys[] = {"steps_per_s", "deg_per_s", "rpm"};
constexpr std::string_view kAccelKeys[] = {"steps_per_s2", "deg_per_s2"};
constexpr std::string_view kJerkKeys[] = {"steps_per_s3", "deg_per_s3"};
constexpr std::string_view kLinearDistanceKeys[] = {"steps", "mm", "rev"};
constexpr std::string_view kLinearSpeedKeys[] = {"steps_per_s", "mm_per_s", "rpm"};
constexpr std::string_view kLinearAccelKeys[] = {"steps_per_s2", "mm_per_s2"};
constexpr std::string_view kLinearJerkKeys[] = {"steps_per_s3", "mm_per_s3"};

struct DimInfo {
  const Unit* units;
  size_t count;
  Keys keys;
  const char* expected;  // the shapes it takes
};
DimInfo dim_info(Dim dim, bool linear) {
  if (linear) {
    switch (dim) {
      case Dim::kDistance:
        return {kLinearDistanceUnits, 3, kLinearDistanceKeys,
                "a number of steps, or an object with one of steps, mm, rev"};
      case Dim::kSpeed:
        return {kLinearSpeedUnits, 3, kLinearSpeedKeys,
                "a number of steps/s, or an object with one of steps_per_s, mm_per_s, rpm"};
      case Dim::kAccel:
        return {kLinearAccelUnits, 2, kLinearAccelKeys,
                "a number of steps/s², or an object with one of steps_per_s2, mm_per_s2"};
      case Dim::kJerk:
        break;
    }
    return {kLinearJerkUnits, 2, kLinearJerkKeys,
            "a number of steps/s³, or an object with one of steps_per_s3, mm_per_s3"};
  }
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

}  // namespace

std::optional<Quantity> QuantityReader::quantity(const Value& v, const std::string& path, Dim dim,
                                                 const Scale& scale) {
  const DimInfo info = dim_info(dim, scale.per_mm > 0);
  Quantity q;
  const Unit* unit = &info.units[0];
  if (v.is(Kind::kNumber)) {
    q.node = &v;
    q.path = path;
  } else if (v.is(Kind::kObject)) {
    if (!r_.known_keys(v, path, info.keys)) return std::nullopt;
    if (v.members.empty()) {
      r_.bad(v, path, info.expected, "a quantity needs a unit");
      return std::nullopt;
    }
    if (v.members.size() > 1) {
      const json::Member& extra = v.members[1];
      r_.add(extra.at, json::path_with_key(path, extra.key), "one unit key", r_.found(extra),
             "one unit only: " + single_quoted(extra.key) + " after " + single_quoted(v.members[0].key));
      return std::nullopt;
    }
    const json::Member& m = v.members[0];
    for (size_t i = 0; i < info.count; ++i) {
      if (info.units[i].key == m.key) unit = &info.units[i];
    }
    q.node = &m.value;
    q.path = json::path_with_key(path, m.key);
    if (!m.value.is(Kind::kNumber)) {
      r_.wrong_type(m.value, q.path, std::string("a number of ") + unit->label);
      return std::nullopt;
    }
  } else {
    r_.wrong_type(v, path, info.expected);
    return std::nullopt;
  }
  const double n = q.node->number;
  q.written = fmt(n) + " " + unit->label;
  // An inverted axis counts distances and positions the other way; a speed is a magnitude.
  const double sign = dim == Dim::kDistance ? scale.sign : 1;
  q.base = unit->through == Through::kBase && sign == 1;
  if (unit->through == Through::kBase) {
    q.value = n * sign;
  } else {
    if (scale.per_degree <= 0) return std::nullopt;
    const double per = unit->through == Through::kDegrees ? scale.per_degree : scale.per_mm;
    q.value = n * unit->factor * per * sign;
    if (!std::isfinite(q.value)) {
      r_.bad(*q.node, q.path, "a value that converts to a finite number of steps", q.written + " is too large");
      return std::nullopt;
    }
  }
  return q;
}

// "90 deg/s (800 steps/s)" or "800 steps/s".
std::string QuantityReader::described(const Quantity& q, const char* base_unit) {
  return q.base ? q.written : q.written + " (" + fmt(q.value) + " " + base_unit + ")";
}

bool QuantityReader::speed_ok(const Quantity& q) {
  const std::string expected = "a speed above 0 and at most " + fmt(kMaxRate) + " steps/s";
  if (q.value <= 0) {
    r_.bad(*q.node, q.path, expected, "speed " + described(q, "steps/s") + " is not above 0");
    return false;
  }
  if (q.value > kMaxRate) {
    r_.bad(*q.node, q.path, expected,
           "speed " + described(q, "steps/s") + " is faster than the board's " + fmt(kMaxRate) + " steps/s");
    return false;
  }
  if (q.value < kMinRate) {
    r_.bad(*q.node, q.path, "a speed of at least one step per 89 s",
           "speed " + described(q, "steps/s") + " is slower than the board can time (one step per 89 s)");
    return false;
  }
  return true;
}

bool QuantityReader::accel_ok(const Quantity& q) {
  if (q.value < 0 || q.value > kMaxAccel) {
    r_.bad(*q.node, q.path, "an acceleration from 0 to " + fmt(kMaxAccel) + " steps/s²",
           "acceleration " + described(q, "steps/s²") + " is out of range");
    return false;
  }
  return true;
}

// A distance or position, within what one STM counts.
bool QuantityReader::steps_ok(const Quantity& q, double rounded) {
  if (std::fabs(rounded) > kMaxSteps) {
    r_.bad(*q.node, q.path, "at most " + fmt(kMaxSteps) + " steps either way",
           described(q, "steps") + " is too far for the board to count");
    return false;
  }
  return true;
}

}  // namespace hmc::motion::reading
