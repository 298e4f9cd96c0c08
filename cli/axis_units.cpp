// Axes by name and quantities with units, turned into the board's moves and back.
#include "axis_units.h"

#include <algorithm>
#include <cmath>

#include "hmc/units.h"
#include "profile_choice.h"

namespace hmc::cli {
namespace {

std::string axes_list(const Profile* profile) {
  if (profile == nullptr || profile->axes.empty()) return "no profile axes (docs/config.md)";
  std::string names;
  for (const Axis& a : profile->axes) names += (names.empty() ? "" : ", ") + a.name + " (" + std::to_string(a.motor) + ")";
  return "the profile's axes are " + names;
}

std::optional<uint32_t> motor_number(const std::string& text) {
  if (text.size() == 1 && text[0] >= '1' && text[0] <= '0' + static_cast<int>(proto::kMotorCount)) {
    return static_cast<uint32_t>(text[0] - '0');
  }
  return std::nullopt;
}

}  // namespace

Result<Axis> resolve_axis(const std::string& text, const Profile* profile, const BoardModel& model, uint32_t steps_per_rev) {
  if (profile != nullptr) {
    if (const Axis* axis = profile->find(text)) return *axis;
  }
  const std::optional<uint32_t> motor = motor_number(text);
  if (!motor) {
    return Error{"no axis '" + text + "': give a motor 1-" + std::to_string(proto::kMotorCount) + " or an axis name; " +
                 axes_list(profile)};
  }
  return plain_motor_axis(*motor, model.motor(*motor).microstep, steps_per_rev);
}

Result<std::vector<uint32_t>> resolve_motors(const std::string& text, const Profile* profile,
                                             const std::vector<uint32_t>& all) {
  if (text == "all") return all;
  std::vector<uint32_t> motors;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string one = text.substr(start, comma - start);
    std::optional<uint32_t> motor = motor_number(one);
    if (!motor && profile != nullptr) {
      if (const Axis* axis = profile->find(one)) motor = axis->motor;
    }
    if (!motor) {
      return Error{"motor must be 1-" + std::to_string(proto::kMotorCount) + ", an axis name or all, not '" + one + "'; " +
                   axes_list(profile)};
    }
    motors.push_back(*motor);
    start = comma + 1;
  }
  return motors;
}

Status send_soft_limits(Session& s, const Axis& axis) {
  const std::optional<SoftLimits> limits = soft_limits_to_send(axis, s.model().motor(axis.motor));
  if (!limits || s.firmware() != Firmware::kV2) return Done{};
  if (SessionResult<BoardFrame> sent = s.execute(*limits); !sent) {
    return Error{"axis '" + axis.name + "': its soft limits were not taken: " + sent.error().message};
  }
  return Done{};
}

std::string axis_position_words(const Axis& axis, const MotorStatus& m) {
  const std::string u = unit_name(axis.unit());
  return axis.name + " at " + number_text(axis.from_board_position(m.position)) + " " + u + " (" +
         steps_text(m.position * axis.microstep) + " steps of 1/" + std::to_string(axis.microstep) + "), " +
         number_text(axis.from_board_rate(m.rate, m.microstep)) + " " + u + "/s" + (m.homed ? ", homed" : ", not homed");
}

nlohmann::json axis_to_json(const Axis& axis, const MotorStatus& m) {
  return {{"axis", axis.name},
          {"motor", axis.motor},
          {"unit", unit_name(axis.unit())},
          {"position", axis.from_board_position(m.position)},
          {"target", axis.from_board_position(m.target)},
          {"steps", static_cast<double>(m.position) * axis.microstep / 256.0},
          {"microstep", axis.microstep},
          {"rate", axis.from_board_rate(m.rate, m.microstep)},
          {"homed", m.homed}};
}

}  // namespace hmc::cli
