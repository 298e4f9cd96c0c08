// Internal to the motion module (planning): one motor's move planned alone — its profile as STM
// stages (ramp_shapes.h) or as our firmware's own trapezoid, the pauses between stages that the
// link and the board add, and, for a coordinated move, the same move slowed to take a given
// time. Also the board's rules for rates, and the words plans use for numbers and profiles.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hmc/command.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "hmc/protocol_facts.h"
#include "hmc/result.h"
#include "ramp_shapes.h"

namespace hmc::motion::planning {

// ---------------------------------------------------------------------------------------
// The board's rules (docs/protocol.md, "What the board does") and the planner's choices

constexpr uint32_t kMinDelayUs = 5;
constexpr uint32_t kMaxDelayUs = 0xFFFFFFFFu / 48u;  // the 48 MHz step timer's 32-bit interval
constexpr uint32_t kMaxRate = proto::kSettings[proto::kSettingMaxRate - 1].max;  // per motor
constexpr uint32_t kBudget = proto::kMaxStepRate;                 // all moving motors together
constexpr uint32_t kRampingBudget = proto::kMaxRampingStepRate;  // ... while any of them ramps
constexpr uint32_t kMaxAccel = proto::kSettings[proto::kSettingAccel - 1].max;
constexpr double kMaxRampS = 1073741824.0 / 48e6;  // the firmware's longest ramp: 2^30 ticks

// The rate the board counts for a delay (it rounds up).
inline uint32_t board_rate(uint32_t delay_us) { return (1000000u + delay_us - 1u) / delay_us; }

// Numbers in words: whole numbers in full, others to two decimals.
std::string num(double x);
// "trapezoid, 2000 steps/s, 8000 steps/s²".
std::string profile_words(const Profile& p);

// Why one motor's move cannot be planned.
struct Problem {
  std::string expected, found, message;
};

struct Piece {
  uint64_t steps;
  uint32_t delay_us;
};

// The length of a command's line, without its line end.
size_t chars(const Command& command);
// The time a line takes on the wire (10 bits a byte), 0 when the link has no baud rate.
inline double wire_s(size_t bytes, uint32_t baud) { return baud == 0 ? 0.0 : static_cast<double>(bytes) * 10.0 / baud; }
double wire_s(const Command& command, uint32_t baud);

// How a slowed motor's move is made to take a given time.
enum class Shape : uint8_t {
  kAsked,      // the file's profile
  kStaircase,  // a ramp the firmware cannot stretch far enough, sampled into stages instead
  kConstant,   // one rate: the last resort for very long stretches
};

struct Fit {
  double target_s = 0;
  Shape shape = Shape::kAsked;
  bool keep_first = false;  // adjust a stage other than the first (its line then keeps its length)
  size_t stm_chars = 0;     // when not 0: the first STM line must keep this length,
  size_t set_chars = 0;     //   and the SET accel line this one (so no other motor's start moves)
  double tolerance_s = 0;   // how far from target_s the move may end
};

// Coordinated motors must end within one step period of each other: each aims for the common
// end within half the shortest step period among them, and never needs to be closer than half
// a step at the board's fastest rate.
constexpr double kSyncToleranceS = 1.0 / kMaxRate;

// What the time between two stages of a motor depends on: the runner sends a stage once it knows
// the one before has ended.
struct LinkTiming {
  uint32_t baud = 0;
  TargetFirmware firmware = TargetFirmware::kV2;
  int64_t start_units = 0;  // where the move starts, 1/256 step (the end events' lengths)
};

// Our firmware: the end event goes out at the board's next main-loop pass, then crosses the
// wire, then the next stage's line does, and the board starts it at its next pass.
constexpr double kBoardLoopS = 100e-6;

// One motor's part of a move.
struct MotorPlan {
  uint32_t motor = 1;
  uint32_t microstep = 16;
  uint32_t dir = proto::kActionForward;
  uint64_t steps = 0;
  std::vector<Piece> pieces;
  bool firmware_ramp = false;  // our firmware ramps: one STM at the top rate after SET accel
  uint32_t accel = 0;
  LinkTiming link;

  // The pause before piece i (i >= 1): with our firmware the end event's and the new line's
  // wire time and the board's main loop; with the seed's, the host's margin on the previous
  // piece's time (session.h) and the line.
  double gap_s(size_t i) const;
  double gaps_s() const;
  double duration_s() const;
  Command stm(size_t i) const {
    return StepperMove{motor, dir, microstep, static_cast<uint32_t>(pieces[i].steps), pieces[i].delay_us};
  }
  // With our firmware every move sets the acceleration first (0: the board must not ramp).
  Command set_accel() const { return SetSetting{motor, proto::kSettingAccel, firmware_ramp ? accel : 0}; }
};

// A stage faster or slower than the board can time, as a Problem naming the motor.
std::optional<Problem> check_rates(const MotorPlan& plan, const std::string& name);
// Fits the pieces after `first` to make the move take `target_s`, the pauses between pieces
// included. Splitting a piece in two adds a pause, which the split must then make up for, so
// both ways are tried — the pieces as they are (one delay for the longest), and split with the
// pause counted — and the closer one kept.
void fit_with_gaps(MotorPlan& plan, size_t first, double fixed_us, double target_s, bool keep_first,
                   double tolerance_s);
// Plans one motor's move of `steps` (> 0) in `dir`. With `fit`, the move is slowed by `r`
// (speed / r, accel / r², jerk / r³: the same shape taking r times as long) and made to take
// fit->target_s; a plan that cannot is a Problem (the caller tries another shape).
Result<MotorPlan, Problem> plan_motor(const Move& move, const MotorConfig& config, uint64_t steps, uint32_t dir,
                                      const LinkTiming& link, double r, const Fit* fit);

}  // namespace hmc::motion::planning
