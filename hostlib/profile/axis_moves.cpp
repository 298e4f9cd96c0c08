// Moves in an axis's own units turned into the board's steps, soft limits and homing settings.
#include "hmc/axis_moves.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hmc/units.h"

namespace hmc {
namespace {

constexpr uint32_t kMaxAccel = proto::kSettings[proto::kSettingAccel - 1].max;

// A quantity for `axis` in steps, with a note when it falls between steps.
Result<StepCount> steps_of(const Axis& axis, const std::string& text, Dimension wanted, const std::string& option,
                           std::vector<std::string>& notes) {
  Result<Quantity> q = parse_quantity(text);
  if (!q) return Error{option + ": " + q.error().message + " (axis '" + axis.name + "' takes " + axis.units_words() + ")"};
  Result<StepCount> steps = axis.to_steps(*q, wanted);
  if (!steps) return Error{option + ": " + steps.error().message};
  if (steps->rounded()) {
    notes.push_back(option + " " + text + " on axis '" + axis.name + "' is " + number_text(steps->exact) + " " +
                    unit_text(Unit::kSteps, wanted) + ": rounded to " + std::to_string(steps->steps));
  }
  return steps;
}

}  // namespace

std::string number_text(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  std::string s = text;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s == "-0" ? "0" : s;
}

Axis plain_motor_axis(uint32_t motor, uint32_t microstep, uint32_t steps_per_rev) {
  Axis axis;
  axis.name = "motor " + std::to_string(motor);
  axis.motor = motor;
  axis.steps_per_rev = steps_per_rev;
  axis.microstep = microstep;
  axis.rotary = true;
  return axis;
}

Result<uint32_t> accel_steps(const Axis& axis, const std::string& text, std::vector<std::string>& notes,
                             const std::string& option) {
  if (!text.empty() && text.find_first_not_of("0123456789") == std::string::npos) {
    const unsigned long long value = std::stoull(text.substr(0, 10));
    if (text.size() > 10 || value > kMaxAccel) {
      return Error{option + " " + text + " steps/s2 is beyond the board's " + std::to_string(kMaxAccel)};
    }
    return static_cast<uint32_t>(value);
  }
  Result<StepCount> steps = steps_of(axis, text, Dimension::kAcceleration, option, notes);
  if (!steps) return steps.error();
  if (steps->steps < 0 || steps->steps > kMaxAccel) {
    return Error{option + " " + text + " is " + std::to_string(steps->steps) + " steps/s2: the board takes 0-" +
                 std::to_string(kMaxAccel)};
  }
  return static_cast<uint32_t>(steps->steps);
}

Result<UnitMove> unit_move(const Axis& axis, const MotorStatus& motor, const UnitMoveRequest& r) {
  const UnitMoveRequest::Names& n = r.names;
  if (r.to.has_value() == r.by.has_value()) return Error{"give the target once: " + n.to + " POSITION or " + n.by + " DISTANCE"};
  UnitMove out;
  const double here = axis.from_board_position(motor.position);
  if (r.to) {
    Result<StepCount> to = steps_of(axis, *r.to, Dimension::kPosition, n.to, out.notes);
    if (!to) return to.error();
    out.target = to->exact / axis.steps_per_unit();
  } else {
    Result<StepCount> by = steps_of(axis, *r.by, Dimension::kPosition, n.by, out.notes);
    if (!by) return by.error();
    out.target = here + by->exact / axis.steps_per_unit();
  }
  // The absolute target in whole steps: the rounding is of this one position, never of a distance.
  const StepCount target = axis.to_board_position(out.target);
  out.target_position = target.steps;
  const int64_t per_step = 256 / axis.microstep;
  const int64_t steps = std::llround(static_cast<double>(target.steps - motor.position) / static_cast<double>(per_step));
  if (std::llabs(steps) > 2147483647) return Error{"the move is more than 2147483647 steps"};
  if (r.speed) {
    // A speed becomes a whole number of microseconds per step, not of steps: said only when
    // that is more than 1 % off.
    std::vector<std::string> unsaid;
    Result<StepCount> speed = steps_of(axis, *r.speed, Dimension::kSpeed, n.speed, unsaid);
    if (!speed) return speed.error();
    if (!(speed->exact > 0)) return Error{n.speed + " must be above 0"};
    out.delay_us = static_cast<uint32_t>(std::max(1LL, std::llround(1e6 / speed->exact)));
    const double actual = 1e6 / *out.delay_us / axis.steps_per_unit();
    const double wanted = speed->exact / axis.steps_per_unit();
    if (std::fabs(actual - wanted) > 0.01 * wanted) {
      out.notes.push_back(n.speed + " " + *r.speed + " on axis '" + axis.name + "' is " + std::to_string(*out.delay_us) +
                          " us per step: " + number_text(actual) + " " + unit_text(axis.unit(), Dimension::kSpeed));
    }
  } else if (axis.speed) {
    out.delay_us = static_cast<uint32_t>(std::llround(1e6 / (*axis.speed * axis.steps_per_unit())));
  }
  if (r.accel) {
    Result<uint32_t> accel = accel_steps(axis, *r.accel, out.notes, n.accel);
    if (!accel) return accel.error();
    out.accel = *accel;
  } else if (axis.accel) {
    out.accel = static_cast<uint32_t>(std::llround(*axis.accel * axis.steps_per_unit()));
  }
  if (steps != 0) {
    StepperMove move;
    move.motor = axis.motor;
    move.dir = steps < 0 ? proto::kActionReverse : proto::kActionForward;
    move.microstep = axis.microstep;
    move.steps = static_cast<uint32_t>(std::llabs(steps));
    move.delay_us = out.delay_us.value_or(0);
    out.move = move;
  }
  return out;
}

HomingSetup homing_setup(const Axis& axis, StepperMove move, UnsetHoming unset) {
  HomingSetup setup;
  if (!axis.homing && unset == UnsetHoming::kKeep) {
    setup.move = move;
    return setup;
  }
  const AxisHoming h = axis.homing.value_or(AxisHoming{});
  const double per_unit = axis.steps_per_unit();
  const auto delay_of = [per_unit](double speed) { return static_cast<uint32_t>(std::llround(1e6 / (speed * per_unit))); };
  if (move.microstep == 0) move.microstep = axis.microstep;
  if (move.delay_us == 0 && h.seek_speed) move.delay_us = delay_of(*h.seek_speed);
  setup.settings.push_back(SetSetting{axis.motor, proto::kSettingHomeEnd, h.end});
  const bool none = unset == UnsetHoming::kNone;
  const std::optional<uint32_t> pull_off =
      h.pull_off ? std::optional<uint32_t>(static_cast<uint32_t>(std::llround(*h.pull_off * per_unit)))
                 : none ? std::optional<uint32_t>(0) : std::nullopt;
  const std::optional<uint32_t> locate = h.locate_speed ? std::optional<uint32_t>(delay_of(*h.locate_speed))
                                         : none         ? std::optional<uint32_t>(0)
                                                        : std::nullopt;
  if (pull_off) setup.settings.push_back(SetSetting{axis.motor, proto::kSettingHomePullOff, *pull_off});
  if (locate) setup.settings.push_back(SetSetting{axis.motor, proto::kSettingHomeLocate, *locate});
  // Zeroed at the switch; a pull-off then backs away from it, toward the other end, and a slow
  // re-approach zeroes it at the switch again (docs/protocol.md, SET home_pull_off).
  if (pull_off && *pull_off == 0) {
    setup.homed_position = 0;
  } else if (pull_off && locate) {
    setup.homed_position = *locate == 0 ? (h.end == 0 ? int64_t{*pull_off} : -int64_t{*pull_off}) : 0;
  }
  setup.move = move;
  return setup;
}

std::optional<SoftLimits> soft_limits_command(const Axis& axis) {
  if (!axis.limit_min) return std::nullopt;
  int64_t low = axis.to_board_position(*axis.limit_min).steps;
  int64_t high = axis.to_board_position(*axis.limit_max).steps;
  if (low > high) std::swap(low, high);  // an inverted axis
  const auto magnitude = [](int64_t v) { return static_cast<uint32_t>(std::llabs(v)); };
  return SoftLimits{axis.motor, low < 0 ? 1u : 0u, magnitude(low), high < 0 ? 1u : 0u, magnitude(high)};
}

std::optional<SoftLimits> soft_limits_to_send(const Axis& axis, const MotorStatus& motor) {
  if (!motor.homed) return std::nullopt;
  return soft_limits_command(axis);
}

std::optional<std::string> beyond_soft_limits(const Axis& axis, const MotorStatus& motor, double target) {
  if (!axis.limit_min || !motor.homed) return std::nullopt;
  if (target >= *axis.limit_min - 1e-9 && target <= *axis.limit_max + 1e-9) return std::nullopt;
  const std::string u = unit_name(axis.unit());
  return "axis '" + axis.name + "': " + number_text(target) + " " + u + " is beyond its soft limits, " +
         number_text(*axis.limit_min) + " to " + number_text(*axis.limit_max) + " " + u + " (the profile's)";
}

SetPosition set_position_command(const Axis& axis, double axis_position) {
  const int64_t board = axis.to_board_position(axis_position).steps;
  return SetPosition{axis.motor, board < 0 ? 1u : 0u, static_cast<uint32_t>(std::llabs(board))};
}

}  // namespace hmc
