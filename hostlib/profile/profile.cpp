// The machine profile read from TOML and checked as a whole: every mistake with its place.
#include "hmc/profile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include <sys/stat.h>
#include <toml++/toml.h>

#include "hmc/command.h"

namespace hmc {
namespace {

constexpr double kRoundingTolerance = 1e-6;  // of a step: closer than this is exact
constexpr uint32_t kMinBaud = 300, kMaxBaud = 4000000;  // as the command line's --baud

ProfilePlace place_of(const toml::source_region& region) { return {region.begin.line, region.begin.column}; }

std::string type_words(toml::node_type type) {
  switch (type) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "true or false";
    default: return "a date or time";
  }
}

// Collects the mistakes of one file.
class Checker {
 public:
  void add(const toml::source_region& where, std::string message) { mistakes_.push_back({place_of(where), std::move(message)}); }
  void add(ProfilePlace where, std::string message) { mistakes_.push_back({where, std::move(message)}); }
  std::vector<ProfileMistake>& mistakes() { return mistakes_; }

  void wrong_type(const toml::node& node, const std::string& what, const std::string& wanted) {
    add(node.source(), what + " must be " + wanted + ", not " + type_words(node.type()));
  }

  std::optional<std::string> string(const toml::node& node, const std::string& what) {
    if (const auto* s = node.as_string()) return s->get();
    wrong_type(node, what, "a string");
    return std::nullopt;
  }
  std::optional<bool> boolean(const toml::node& node, const std::string& what) {
    if (const auto* b = node.as_boolean()) return b->get();
    wrong_type(node, what, "true or false");
    return std::nullopt;
  }
  std::optional<int64_t> integer(const toml::node& node, const std::string& what, int64_t low, int64_t high) {
    const auto* i = node.as_integer();
    if (i == nullptr) {
      wrong_type(node, what, "a whole number");
      return std::nullopt;
    }
    if (i->get() < low || i->get() > high) {
      add(node.source(), what + " must be " + std::to_string(low) + "-" + std::to_string(high) + ", not " +
                             std::to_string(i->get()));
      return std::nullopt;
    }
    return i->get();
  }
  std::optional<double> positive_number(const toml::node& node, const std::string& what) {
    std::optional<double> value;
    if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
    if (const auto* f = node.as_floating_point()) value = f->get();
    if (!value) {
      wrong_type(node, what, "a number");
      return std::nullopt;
    }
    if (!(*value > 0) || !std::isfinite(*value)) {
      add(node.source(), what + " must be above 0");
      return std::nullopt;
    }
    return value;
  }
  // A length in mm: "2mm" or a bare number of mm (the drive's sizes, known before the axis's steps).
  std::optional<double> length(const toml::node& node, const std::string& what) {
    std::optional<double> mm;
    if (const auto* s = node.as_string()) {
      Result<Quantity> q = parse_quantity(s->get());
      if (!q) {
        add(node.source(), what + ": " + q.error().message);
        return std::nullopt;
      }
      if (q->unit != Unit::kMm || q->dimension != Dimension::kPosition) {
        add(node.source(), what + " is a length: give it in mm, not " + unit_text(q->unit, q->dimension));
        return std::nullopt;
      }
      mm = q->value;
    } else if (node.is_number()) {
      mm = node.value<double>();
    } else {
      wrong_type(node, what, "a length (\"2mm\" or a number of mm)");
      return std::nullopt;
    }
    if (!(*mm > 0)) {
      add(node.source(), what + " must be above 0 mm");
      return std::nullopt;
    }
    return mm;
  }
  // A quantity for `axis` in its own units: "250mm", "0.5rev", "20mm/s", or a bare number of them.
  std::optional<double> quantity(const toml::node& node, const Axis& axis, Dimension wanted, const std::string& what) {
    if (node.is_number()) return node.value<double>();
    const auto* s = node.as_string();
    if (s == nullptr) {
      wrong_type(node, what, "a quantity (\"" + std::string(wanted == Dimension::kPosition ? "250" : "20") +
                                 unit_text(axis.unit(), wanted) + "\" or a number of " + unit_text(axis.unit(), wanted) + ")");
      return std::nullopt;
    }
    Result<Quantity> q = parse_quantity(s->get());
    if (!q) {
      add(node.source(), what + ": " + q.error().message);
      return std::nullopt;
    }
    Result<StepCount> steps = axis.to_steps(*q, wanted);
    if (!steps) {
      add(node.source(), what + ": " + steps.error().message);
      return std::nullopt;
    }
    return steps->exact / axis.steps_per_unit();
  }

  void unknown_key(const toml::key& key, const std::string& where, const char* known) {
    add(key.source(), "unknown key '" + std::string(key.str()) + "' " + where + " (known: " + known + ")");
  }

 private:
  std::vector<ProfileMistake> mistakes_;
};

bool valid_axis_name(std::string_view name) {
  if (name.empty() || name == "all" || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  }
  return true;
}

void read_homing(Checker& check, const toml::table& table, Axis& axis) {
  const std::string in = "in axis '" + axis.name + "' homing";
  AxisHoming homing;
  for (const auto& [key, node] : table) {
    const std::string what = "homing " + std::string(key.str());
    if (key == "end") {
      if (std::optional<std::string> end = check.string(node, what)) {
        if (*end == "reverse" || *end == "forward") {
          homing.end = *end == "forward" ? 1u : 0u;
        } else {
          check.add(node.source(), "homing end must be \"reverse\" or \"forward\" (the motor's switch), not \"" + *end + "\"");
        }
      }
    } else if (key == "seek_speed") {
      homing.seek_speed = check.quantity(node, axis, Dimension::kSpeed, what);
    } else if (key == "pull_off") {
      homing.pull_off = check.quantity(node, axis, Dimension::kPosition, what);
    } else if (key == "locate_speed") {
      homing.locate_speed = check.quantity(node, axis, Dimension::kSpeed, what);
    } else {
      check.unknown_key(key, in, "end, seek_speed, pull_off, locate_speed");
    }
  }
  for (const std::optional<double>* speed : {&homing.seek_speed, &homing.locate_speed}) {
    if (*speed && !(**speed > 0)) check.add(table.source(), "axis '" + axis.name + "': homing speeds must be above 0");
  }
  if (homing.pull_off && *homing.pull_off < 0) check.add(table.source(), "axis '" + axis.name + "': homing pull_off must not be negative");
  if (!proto::motor_has_switches(axis.motor)) {
    check.add(table.source(), "axis '" + axis.name + "': motor " + std::to_string(axis.motor) +
                                  " has no limit switches, so it cannot home (zero it instead: hmc zero " + axis.name + ")");
  }
  axis.homing = homing;
}

std::optional<Axis> read_axis(Checker& check, const toml::key& name, const toml::table& table) {
  Axis axis;
  axis.name = std::string(name.str());
  axis.place = place_of(name.source());
  const size_t mistakes_before = check.mistakes().size();
  if (!valid_axis_name(axis.name)) {
    check.add(name.source(), "axis name '" + axis.name +
                                 "' must start with a letter and hold only letters, digits, '-' and '_' (and not be 'all')");
  }
  const std::string of = "axis '" + axis.name + "' ";
  // First what the steps per unit depend on; then the quantities, which need them.
  bool has_motor = false;
  int drives = 0;
  std::optional<uint32_t> pulley_teeth;
  std::optional<double> belt_pitch;
  const toml::node* belt_place = nullptr;
  for (const auto& [key, node] : table) {
    const std::string what = of + std::string(key.str());
    if (key == "motor") {
      if (auto m = check.integer(node, what, 1, proto::kMotorCount)) axis.motor = static_cast<uint32_t>(*m);
      has_motor = true;
    } else if (key == "steps_per_rev") {
      if (auto s = check.integer(node, what, 1, 100000)) axis.steps_per_rev = static_cast<uint32_t>(*s);
    } else if (key == "microstep") {
      if (auto m = check.integer(node, what, 1, 256)) {
        if ((*m & (*m - 1)) != 0) {
          check.add(node.source(), what + " must be 1, 2, 4, 8, 16, 32, 64, 128 or 256, not " + std::to_string(*m));
        } else {
          axis.microstep = static_cast<uint32_t>(*m);
        }
      }
    } else if (key == "gear_ratio") {
      if (auto g = check.positive_number(node, what)) axis.gear_ratio = *g;
    } else if (key == "invert") {
      if (auto b = check.boolean(node, what)) axis.invert = *b;
    } else if (key == "rotary") {
      if (auto b = check.boolean(node, what)) {
        axis.rotary = *b;
        if (*b) ++drives;
      }
    } else if (key == "mm_per_rev") {
      ++drives;
      if (auto mm = check.length(node, what)) axis.mm_per_rev = *mm;
    } else if (key == "screw_lead") {
      ++drives;
      if (auto mm = check.length(node, what)) axis.mm_per_rev = *mm;
    } else if (key == "pulley_teeth") {
      if (auto t = check.integer(node, what, 1, 10000)) pulley_teeth = static_cast<uint32_t>(*t);
      belt_place = &node;
    } else if (key == "belt_pitch") {
      belt_pitch = check.length(node, what);
      belt_place = &node;
    } else if (key == "limits" || key == "speed" || key == "accel" || key == "homing") {
      // read below, once the steps per unit are known
    } else {
      check.unknown_key(key, "in " + of.substr(0, of.size() - 1),
                        "motor, steps_per_rev, microstep, gear_ratio, mm_per_rev, pulley_teeth, belt_pitch, screw_lead, "
                        "rotary, invert, limits, speed, accel, homing");
    }
  }
  if (belt_place != nullptr) {
    ++drives;
    if (table.contains("pulley_teeth") != table.contains("belt_pitch")) {
      check.add(belt_place->source(), of + "needs both pulley_teeth and belt_pitch for a belt drive");
    } else if (pulley_teeth && belt_pitch) {
      axis.mm_per_rev = *pulley_teeth * *belt_pitch;
    }
  }
  if (!has_motor) check.add(name.source(), of + "has no motor (1-" + std::to_string(proto::kMotorCount) + ")");
  if (drives != 1) {
    check.add(name.source(), of + (drives == 0 ? "has no drive" : "has more than one drive") +
                                 ": give exactly one of mm_per_rev, pulley_teeth with belt_pitch, screw_lead, or rotary = true");
  }
  const bool drive_known = drives == 1 && (axis.rotary || axis.mm_per_rev > 0);
  if (!drive_known) return std::nullopt;  // its quantities cannot be judged

  for (const auto& [key, node] : table) {
    const std::string what = of + std::string(key.str());
    if (key == "speed") {
      axis.speed = check.quantity(node, axis, Dimension::kSpeed, what);
      if (axis.speed && !(*axis.speed > 0)) check.add(node.source(), what + " must be above 0");
    } else if (key == "accel") {
      axis.accel = check.quantity(node, axis, Dimension::kAcceleration, what);
      if (axis.accel && *axis.accel < 0) check.add(node.source(), what + " must not be negative (0: constant rate)");
    } else if (key == "limits") {
      const auto* list = node.as_array();
      if (list == nullptr || list->size() != 2) {
        check.add(node.source(), what + " must be [low, high], such as [\"0" + std::string(unit_name(axis.unit())) +
                                     "\", \"250" + unit_name(axis.unit()) + "\"]");
        continue;
      }
      const std::optional<double> low = check.quantity(*list->get(0), axis, Dimension::kPosition, what + " low");
      const std::optional<double> high = check.quantity(*list->get(1), axis, Dimension::kPosition, what + " high");
      if (low && high && !(*low < *high)) {
        check.add(node.source(), what + " are the wrong way round: the low limit must come first and be below the high one");
      } else if (low && high) {
        axis.limit_min = low;
        axis.limit_max = high;
      }
    } else if (key == "homing") {
      if (const auto* homing = node.as_table()) {
        read_homing(check, *homing, axis);
      } else {
        check.wrong_type(node, what, "a table ([axis." + axis.name + ".homing])");
      }
    }
  }
  if (check.mistakes().size() != mistakes_before) return std::nullopt;
  return axis;
}

}  // namespace

bool StepCount::rounded() const { return std::fabs(exact - static_cast<double>(steps)) > kRoundingTolerance; }

std::string Axis::units_words() const { return std::string(unit_name(unit())) + ", rev or steps"; }

double Axis::steps_per_rev_out() const { return static_cast<double>(steps_per_rev) * microstep * gear_ratio; }

double Axis::steps_per_unit() const { return steps_per_rev_out() / (rotary ? 360.0 : mm_per_rev); }

Result<StepCount> Axis::to_steps(const Quantity& q, Dimension wanted) const {
  if (q.dimension != wanted) {
    return Error{"'" + unit_text(q.unit, q.dimension) + "' is " + dimension_words(q.dimension) + ", but " +
                 dimension_words(wanted) + " is wanted here (" + unit_text(unit(), wanted) + ")"};
  }
  double steps = 0;
  switch (q.unit) {
    case Unit::kSteps: steps = q.value; break;
    case Unit::kRev: steps = q.value * steps_per_rev_out(); break;
    case Unit::kMm:
    case Unit::kDeg:
      if (q.unit != unit()) {
        return Error{"axis '" + name + "' is " + (rotary ? "rotary" : "linear") + ": it takes " +
                     unit_text(unit(), wanted) + ", rev or steps" + (wanted == Dimension::kPosition ? "" : " (per second)") +
                     ", not " + unit_name(q.unit)};
      }
      steps = q.value * steps_per_unit();
      break;
  }
  if (!std::isfinite(steps) || std::fabs(steps) > 2147483647.0) {
    return Error{"axis '" + name + "': " + std::to_string(q.value) + " " + unit_text(q.unit, q.dimension) +
                 " is beyond the board's 2147483647 steps"};
  }
  return StepCount{std::llround(steps), steps};
}

StepCount Axis::to_board_position(double axis_position) const {
  const double steps = axis_position * steps_per_unit() * (invert ? -1 : 1);
  const int64_t whole = std::llround(steps);
  return StepCount{whole * static_cast<int64_t>(256 / microstep), steps * (256.0 / microstep)};
}

double Axis::from_board_position(int64_t position) const {
  return static_cast<double>(position) / (256.0 / microstep) / steps_per_unit() * (invert ? -1 : 1);
}

double Axis::from_board_rate(uint32_t rate, uint32_t at_microstep) const {
  return static_cast<double>(rate) * (static_cast<double>(microstep) / at_microstep) / steps_per_unit();
}

const Axis* Profile::find(std::string_view name_or_motor) const {
  for (const Axis& a : axes) {
    if (a.name == name_or_motor || std::to_string(a.motor) == name_or_motor) return &a;
  }
  return nullptr;
}

const Axis* Profile::axis_of_motor(uint32_t motor) const {
  for (const Axis& a : axes) {
    if (a.motor == motor) return &a;
  }
  return nullptr;
}

std::string ProfileError::text() const {
  std::string out;
  for (const ProfileMistake& m : mistakes) {
    out += path;
    if (m.place.line > 0) out += ":" + std::to_string(m.place.line) + ":" + std::to_string(m.place.column);
    out += ": " + m.message + "\n";
  }
  return out;
}

Result<Profile, ProfileError> parse_profile(std::string_view text, const std::string& path) {
  toml::table root;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    ProfileError error{path, false, true, {}};
    error.mistakes.push_back({place_of(e.source()), "TOML syntax: " + std::string(e.description()) +
                                                       " (the reader stops here: later mistakes are not yet known)"});
    return error;
  }
  Checker check;
  Profile profile;
  profile.path = path;
  std::map<uint32_t, const Axis*> by_motor;
  std::vector<Axis> axes;
  for (const auto& [key, node] : root) {
    if (key == "port") {
      profile.port = check.string(node, "port");
      if (profile.port && profile.port->empty()) check.add(node.source(), "port must not be empty (leave it out to find the board)");
    } else if (key == "baud") {
      if (auto b = check.integer(node, "baud", kMinBaud, kMaxBaud)) profile.baud = static_cast<uint32_t>(*b);
    } else if (key == "firmware") {
      profile.firmware = check.string(node, "firmware");
      if (profile.firmware && *profile.firmware != "auto" && *profile.firmware != "v2" && *profile.firmware != "seed") {
        check.add(node.source(), "firmware must be \"auto\", \"v2\" or \"seed\", not \"" + *profile.firmware + "\"");
      }
    } else if (key == "axis") {
      const auto* table = node.as_table();
      if (table == nullptr) {
        check.wrong_type(node, "axis", "a table of axes ([axis.NAME])");
        continue;
      }
      for (const auto& [name, axis_node] : *table) {
        const auto* axis_table = axis_node.as_table();
        if (axis_table == nullptr) {
          check.wrong_type(axis_node, "axis '" + std::string(name.str()) + "'", "a table ([axis." + std::string(name.str()) + "])");
          continue;
        }
        if (std::optional<Axis> axis = read_axis(check, name, *axis_table)) axes.push_back(*axis);
      }
    } else {
      check.unknown_key(key, "at the top", "port, baud, firmware, axis");
    }
  }
  // A motor driving two axes, reported where it is named the second time in the file.
  if (const auto* table = root["axis"].as_table()) {
    std::vector<std::pair<const toml::node*, std::string>> motors;
    for (const auto& [name, axis_node] : *table) {
      const auto* axis_table = axis_node.as_table();
      const toml::node* motor = axis_table ? axis_table->get("motor") : nullptr;
      if (motor != nullptr && motor->is_integer()) motors.emplace_back(motor, std::string(name.str()));
    }
    std::sort(motors.begin(), motors.end(), [](const auto& a, const auto& b) {
      return a.first->source().begin < b.first->source().begin;
    });
    std::map<int64_t, std::pair<std::string, uint32_t>> seen;  // motor -> axis, line
    for (const auto& [motor, name] : motors) {
      const int64_t m = motor->as_integer()->get();
      const auto [it, fresh] = seen.emplace(m, std::make_pair(name, motor->source().begin.line));
      if (!fresh) {
        check.add(motor->source(), "motor " + std::to_string(m) + " is named twice: by axis '" + it->second.first +
                                       "' (line " + std::to_string(it->second.second) + ") and by axis '" + name + "'");
      }
    }
  }
  std::stable_sort(check.mistakes().begin(), check.mistakes().end(), [](const ProfileMistake& a, const ProfileMistake& b) {
    return a.place.line != b.place.line ? a.place.line < b.place.line : a.place.column < b.place.column;
  });
  if (!check.mistakes().empty()) return ProfileError{path, false, false, std::move(check.mistakes())};
  std::sort(axes.begin(), axes.end(), [](const Axis& a, const Axis& b) { return a.motor < b.motor; });
  profile.axes = std::move(axes);
  return profile;
}

Result<Profile, ProfileError> load_profile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  if (file) text << file.rdbuf();
  if (!file) {
    return ProfileError{path, true, false, {{ProfilePlace{}, "cannot read the profile (hmc config path says where it is looked for)"}}};
  }
  return parse_profile(text.str(), path);
}

Result<std::string> default_profile_path() {
  const char* config = std::getenv("XDG_CONFIG_HOME");
  if (config != nullptr && config[0] == '/') return std::string(config) + "/hmc/config.toml";
  const char* home = std::getenv("HOME");
  if (home == nullptr || home[0] == '\0') return Error{"neither XDG_CONFIG_HOME nor HOME is set: name the profile with --profile"};
  return std::string(home) + "/.config/hmc/config.toml";
}

Result<ProfileSource> find_profile(const std::string& given) {
  const auto exists = [](const std::string& path) {
    struct stat info {};
    return stat(path.c_str(), &info) == 0;
  };
  if (!given.empty()) return ProfileSource{given, "--profile", exists(given)};
  if (const char* env = std::getenv("HMC_PROFILE"); env != nullptr && env[0] != '\0') {
    return ProfileSource{env, "HMC_PROFILE", exists(env)};
  }
  Result<std::string> path = default_profile_path();
  if (!path) return path.error();
  return ProfileSource{*path, "default", exists(*path)};
}

}  // namespace hmc
