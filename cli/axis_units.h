// Axes on the command line: an axis named by the profile or a motor number, moves given in its
// units (`--to 250mm`, `--by -90deg`, `--speed 20mm/s`, `--accel 100mm/s2`) turned into the
// board's steps, and positions shown back in its units (docs/config.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hmc/command.h"
#include "hmc/profile.h"
#include "hmc/session.h"

namespace hmc::cli {

// The axis `text` names: a profile axis by name, or by its motor number; a motor no profile axis
// drives is a rotary axis of `steps_per_rev` full steps at the motor's current microstep (so
// deg, rev and steps work on any motor). Names no axis: an error listing the axes there are.
Result<Axis> resolve_axis(const std::string& text, const Profile* profile, const BoardModel& model,
                          uint32_t steps_per_rev = 200);

// The motors "1", "slide", "1,slide" or "all" mean; `all` is the motors given.
Result<std::vector<uint32_t>> resolve_motors(const std::string& text, const Profile* profile,
                                             const std::vector<uint32_t>& all);

struct UnitMoveRequest {
  std::optional<std::string> to, by;  // exactly one: an absolute position or a distance
  std::optional<std::string> speed;   // default: the axis's speed (else the caller's delay)
  std::optional<std::string> accel;   // a number (steps/s^2) or a quantity; default: the axis's
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

// A step count for the acceleration option: "8000" (steps/s^2 as before) or "100mm/s2".
Result<uint32_t> accel_steps(const Axis& axis, const std::string& text, std::vector<std::string>& notes);

// Homing `axis` as its profile says: the settings to SET first (the switch end, the pull-off and
// the slow re-approach) and the homing move (its microstep; its delay from the seek speed),
// keeping what the command line gave in `move` (a microstep or delay other than 0).
struct HomingSetup {
  std::vector<SetSetting> settings;
  StepperMove move;
};
HomingSetup homing_setup(const Axis& axis, StepperMove move);

// Sends the axis's soft limits (LIM, in the board's positions) when its position means
// something — the motor homed or zeroed since power-up — as grbl enforces limits only then; does
// nothing for an axis without limits, an unreferenced motor, or the seed firmware.
Status send_soft_limits(Session& session, const Axis& axis);

// "slide at 250 mm (20000 steps of 1/16)" and its JSON, for an axis of the profile.
std::string axis_position_words(const Axis& axis, const MotorStatus& motor);
nlohmann::json axis_to_json(const Axis& axis, const MotorStatus& motor);

}  // namespace hmc::cli
