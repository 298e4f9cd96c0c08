// Axes on the command line: an axis named by the profile or a motor number, moves given in its
// units (`--to 250mm`, `--by -90deg`, `--speed 20mm/s`, `--accel 100mm/s2`) turned into the
// board's steps, and positions shown back in its units (docs/config.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hmc/axis_moves.h"
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

// Moves in units (unit_move), soft limits and homing setups are libhmc's: hmc/axis_moves.h,
// shared with the Python module.

// Sends the axis's soft limits (LIM, in the board's positions) when its position means
// something — the motor homed or zeroed since power-up — as grbl enforces limits only then; does
// nothing for an axis without limits, an unreferenced motor, or the seed firmware.
Status send_soft_limits(Session& session, const Axis& axis);

// "slide at 250 mm (20000 steps of 1/16)" and its JSON, for an axis of the profile.
std::string axis_position_words(const Axis& axis, const MotorStatus& motor);
nlohmann::json axis_to_json(const Axis& axis, const MotorStatus& motor);

}  // namespace hmc::cli
