// Moves in an axis's own units: a target, distance, speed and acceleration given as quantities
// ("250mm", "-90deg", "20mm/s", "100mm/s2") turned into the board's STM and settings, the
// profile's soft limits judged and sent as LIM, and homing as the profile describes it
// (docs/config.md). Shared by the command line and the Python module, so a move means the same
// steps from both.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/command.h"
#include "hmc/profile.h"
#include "hmc/result.h"

namespace hmc {

// The delay per step of a move given no speed: 500 us (2000 steps/s), as `hmc move` has always used.
inline constexpr uint32_t kDefaultMoveDelayUs = 500;
// Full steps per turn of a motor no profile axis describes (a 1.8-degree stepper).
inline constexpr uint32_t kDefaultStepsPerRev = 200;

// A number for people: at most `decimals` decimals, trailing zeros dropped ("250", "26.667").
std::string number_text(double value, int decimals = 3);

// The axis of a motor no profile axis drives: rotary, `steps_per_rev` full steps a turn, at the
// motor's current microstep, so deg, rev and steps work on any motor.
Axis plain_motor_axis(uint32_t motor, uint32_t microstep, uint32_t steps_per_rev = kDefaultStepsPerRev);

struct UnitMoveRequest {
  std::optional<std::string> to, by;  // exactly one: an absolute position or a distance
  std::optional<std::string> speed;   // default: the axis's speed (else the caller's delay)
  std::optional<std::string> accel;   // a number (steps/s^2) or a quantity; default: the axis's
  // How the caller names these values in messages: "--to" on the command line, "to=" in Python.
  struct Names {
    std::string to = "--to", by = "--by", speed = "--speed", accel = "--accel";
  };
  Names names{};
};

struct UnitMove {
  std::optional<StepperMove> move;     // none when the axis is already there
  std::optional<uint32_t> accel;       // steps/s^2 to SET first
  std::optional<uint32_t> delay_us;    // from the speed; none: the caller's default
  double target = 0;                   // axis units
  int64_t target_position = 0;         // the board's position at the end, 1/256 step
  std::vector<std::string> notes;      // values rounded to whole steps, said to the user
};

// The move that brings `axis` from where `motor` is to the target, or why not: a unit the axis
// does not have, a speed where a position is wanted.
Result<UnitMove> unit_move(const Axis& axis, const MotorStatus& motor, const UnitMoveRequest& request);

// Why `target` (axis units) is refused: beyond the axis's soft limits. Judged only where the
// position means something (the motor homed since power-up); nullopt when it may go there.
std::optional<std::string> beyond_soft_limits(const Axis& axis, const MotorStatus& motor, double target);

// A step count for an acceleration: "8000" (steps/s^2) or "100mm/s2"; `option` names it in messages.
Result<uint32_t> accel_steps(const Axis& axis, const std::string& text, std::vector<std::string>& notes,
                             const std::string& option = "--accel");

// Homing `axis` as its profile says: the settings to SET first (the switch end, the pull-off and
// the slow re-approach) and the homing move (its microstep; its delay from the seek speed),
// keeping what the caller gave in `move` (a microstep or delay other than 0).
struct HomingSetup {
  std::vector<SetSetting> settings;
  StepperMove move;
  // Where homing leaves the motor, in steps at move.microstep (the board zeroes at the switch; a
  // pull-off without a slow re-approach ends that far off it), when the settings sent decide it;
  // nullopt when the board's own settings do.
  std::optional<int64_t> homed_position;
};
// A pull-off or slow re-approach the profile leaves out: kept as the board has it (`hmc home`,
// Python: what the user SET stays), or set to none by a program that owns the board while it runs
// and must know where homing leaves the motor (grbl, a motion file's `home`).
enum class UnsetHoming : uint8_t { kKeep, kNone };
HomingSetup homing_setup(const Axis& axis, StepperMove move, UnsetHoming unset = UnsetHoming::kKeep);

// The axis's soft limits as the board's LIM (1/256-step positions, an inverted axis's swapped);
// nullopt for an axis without limits. Send it only once the motor is homed or zeroed: before
// that its position is wherever it stood at power-up (grbl enforces limits only then too).
std::optional<SoftLimits> soft_limits_command(const Axis& axis);
// The LIM to send for `axis` now: its limits once `motor` is homed or zeroed, else nullopt.
std::optional<SoftLimits> soft_limits_to_send(const Axis& axis, const MotorStatus& motor);

// The board's POS that makes a resting motor's position `axis_position` (axis units) from now on:
// 0 zeroes it here. One conversion for `hmc zero`, `hmc jog`'s z and hmc-desk's "set zero here".
SetPosition set_position_command(const Axis& axis, double axis_position);

}  // namespace hmc
