// What the parts of the grbl front end share (grbl.cpp: lines and G-code; grbl_motion.cpp: moves
// and homing on the board; grbl_reports.cpp: status reports and settings). Not installed.
#pragma once

#include <string>

#include "hmc/grbl.h"
#include "hmc/protocol_facts.h"

namespace hmc::grbl::detail {

inline constexpr double kMmPerInch = 25.4;
// Rates: every motor's under the board's budget for motors stepping at once while one ramps
// (protocol_facts.h: 150 000 steps/s, the same as at constant rate).
inline constexpr double kRampBudget = proto::kMaxRampingStepRate;
inline constexpr double kFlatBudget = proto::kMaxStepRate;
// Without a profile speed or acceleration: one turn of a 200-step motor at 1/16 per second, and
// that rate reached in a quarter of a second.
inline constexpr double kDefaultRate = 3200;   // steps/s
inline constexpr double kDefaultAccel = 12800;  // steps/s^2

inline constexpr char kLetters[kAxisCount] = {'X', 'Y', 'Z'};

inline bool moving(const MotorStatus& m) { return m.state != MotorState::kIdle; }

inline std::string fmt(double v, int decimals = 3) { return fixed(v, decimals); }

}  // namespace hmc::grbl::detail
