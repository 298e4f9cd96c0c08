// Motion planning: a motion file turned into what will be sent and when, and what every motor
// will do over time, before anything moves (`hmc plan`, `hmc run --dry-run`), and the same plan
// carried out by the runner (motion_runner.h).
//
// Profiles become STM stages, each a run of steps at one integer delay: the constant rate is one
// stage; the seed's staged ramp (seed 000: low -> mid -> high -> mid -> low, generalised to N
// rates) is 2N-1 stages; a trapezoid or S-curve is, with our firmware, one STM after setting the
// firmware's acceleration (trapezoid), or, otherwise, its velocity sampled into stages. Either
// way the planned timeline is the same profile. Coordinated moves scale every motor's profile to
// the longest one's duration so all arrive together (within one step period).
//
// The rules (docs/motion-files.md, "How moves are planned"):
//  - Time runs from the start of the file; an action starts when the previous one ends. A move
//    that does not wait ends at once while its motor keeps moving; a later action that moves it,
//    homing (every motor must rest), a `wait until_done`, and with the seed's firmware a servo
//    or LED action (seed rule [5]) first wait until the motors concerned rest.
//  - A motor starts when its STM line has arrived: setup lines go first, then one STM per motor,
//    each taking (frame length + 1)·10/baud seconds on the wire (sum checksums).
//  - Staged ramp, N rates r_k = speed·k/N: each of the N-1 ramp stages on either side takes the
//    steps an ideal ramp at `accel` spends between r_(k-1) and r_k, or distance/(4N) without an
//    acceleration (at least 1 step); the top stage takes the rest. Ramps too long for the
//    distance shrink in proportion; a distance below 2N-1 steps uses the lowest (d+1)/2 rates.
//  - Our firmware's trapezoid: SET accel, then one STM (a move too short to reach its speed is
//    sent at its peak speed: the same motion). What the board cannot ramp (longer than 22 s,
//    an acceleration rounding to 0 or above its range) is planned as stages instead.
//  - Sampled profiles (trapezoid with the seed's firmware: 8 slices per ramp; S-curve: 12):
//    the ramp is cut at equal times, each slice a stage of its whole steps at its mean rate.
//  - Homing has no known duration: 0.5 s per motor is assumed (Action::estimated). A profile
//    axis homes as its profile says (axis_moves.h's homing_setup, as `hmc home`): the settings
//    first, a pull-off or re-approach the profile leaves out set to none, so that where homing
//    leaves the motor is known; then, with our firmware, its soft limits (LIM).
//  - A stop ends when its motors rest: at once at constant rate, after braking at the
//    acceleration set on the board otherwise; a stopped motor's position is unknown after.
//  - Coordinated: every motor ends at the same time E = max(start_k + own duration_k); a motor
//    that would finish earlier is slowed (speed / r, accel / r², jerk / r³), then its longest
//    stage is split into runs at delays d and d + 1 (our firmware's trapezoid: delay and
//    acceleration chosen together), so that it ends within 10 µs of E: within one step period
//    of every other motor. When that shape cannot be stretched, stages, then one rate.
//  - Rates: every stage at most 50 000 steps/s and at least one step per 89 s; the rates of
//    motors stepping at once within the board's budgets (VER: 150 000 steps/s in all on this
//    firmware, ramping or not; an older board's own).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hmc/protocol_facts.h"
#include "hmc/board_frame.h"
#include "hmc/command.h"
#include "hmc/motion_file.h"
#include "hmc/result.h"

namespace hmc::motion {

// One STM a motor runs to its end before the next: `steps` steps of `delay_us`.
struct Stage {
  uint32_t motor = 1;
  uint32_t dir = proto::kActionForward;
  uint32_t microstep = 16;
  uint32_t steps = 0;
  uint32_t delay_us = 0;
  double start_s = 0;  // planned, from the start of the file
  double end_s = 0;
};

// A point of a motor's velocity over time (steps/s, signed; piecewise linear between points).
struct VelocityPoint {
  double t_s = 0;
  double velocity = 0;
};

enum class ActionKind : uint8_t { kHome, kMove, kServo, kLed, kWait, kStop };

// One thing the runner does, in order; repeats are unrolled.
struct Action {
  ActionKind kind = ActionKind::kMove;
  size_t index = 0;         // 1-based position in the unrolled list: "step k of n"
  std::string description;  // "move pan 1600 steps, trapezoid to 2000 steps/s", or the step's label
  Location where;           // the file step it comes from
  double start_s = 0;       // planned start, from the start of the file
  double end_s = 0;         // planned end (homing: an estimate)
  // Settings to send first (with our firmware: the acceleration of each moving motor).
  std::vector<Command> setup;
  // Moves: each motor's stages, run one after another; stages of different motors run at once.
  std::vector<std::vector<Stage>> stages;
  // Everything else the action sends, in order: HOME, SVM, LED frames (a fade: one per
  // `commands_at_s` entry), stops.
  std::vector<Command> commands;
  std::vector<double> commands_at_s;  // planned send time of each entry of `commands`
  bool wait_for_motors = true;        // the action ends when its motors rest (moves, home, stop)
  std::vector<uint32_t> motors;       // the motors it moves or waits for
  std::vector<int64_t> homed_at;      // homing: where each of `motors` stands once homed (steps)
  bool estimated = false;             // end_s is a guess (homing takes as long as the switch)
};

struct MotorTrack {
  std::string name;
  uint32_t motor = 1;
  uint32_t microstep = 16;
  std::vector<VelocityPoint> velocity;
  int64_t start_position = 0;  // steps: the whole step the plan counts from
  double start_exact = 0;      // where the motor stood (a fraction: between two steps)
  int64_t end_position = 0;
  bool start_known = true;     // false: the position is not known (not homed, or stopped mid-move);
  bool end_known = true;       //   the position then counts from wherever the motor was
  std::vector<double> stage_boundaries_s;  // when a stage (of a staged/sampled profile) begins
};

struct Plan {
  std::vector<Action> actions;
  std::vector<MotorTrack> tracks;
  double duration_s = 0;
};

enum class TargetFirmware : uint8_t { kV2, kSeed };

struct PlanOptions {
  TargetFirmware firmware = TargetFirmware::kV2;
  // Start positions (steps at each motor's microstep) of motors 1-3, when known; absolute moves
  // before a home need them. A board that stands between two steps of the motor's microstep (moved
  // at a finer one) gives a fraction: the plan counts from the nearest whole step, and a position
  // becomes the whole number of steps that brings the motor nearest it.
  std::optional<double> start_position[proto::kMotorCount];
  uint32_t baud = 115200;  // frame wire times, for when coordinated motors start
  StepBudgets budgets;     // the board's (Session::step_budgets_in_force), else this firmware's
};

// Plans a validated file. Errors (an absolute move before the motor's position is known, a
// move beyond its soft limits, a rate the board cannot time) name the step's location.
Result<Plan, std::vector<FileError>> plan_motion(const MotionFile& file, const PlanOptions& options);

// Velocity over time as an SVG a person can open: one panel per motor, stage boundaries marked.
std::string plot_svg(const Plan& plan, const std::string& title);
// t_s,motor,name,velocity rows, every track point.
std::string plot_csv(const Plan& plan);

}  // namespace hmc::motion
