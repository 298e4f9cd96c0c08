// Internal to the motion module: planning as part of checking a file that has mistakes, so that
// one run reports both kinds (motion_file.h). The file's sound steps are planned; each broken
// step that may move motors stands in them as a placeholder at its location, after which no
// motor's position is followed until it is homed or sent to an absolute position (a mistake
// found from a position the broken step might have changed would be a guess); nor is a stopped
// motor's, since only timing tells where a stop cuts a move. Only mistakes of position are
// found, each once: a `to` before the position is known, a move beyond a soft limit, a move
// longer than one STM counts. Rates and timings depend on the broken values, so they wait for
// the planning of the mended file; positions alone are followed, so this is quick.
#pragma once

#include <vector>

#include "hmc/motion_file.h"

namespace hmc::motion::planning {

std::vector<FileError> position_mistakes(const MotionFile& partial, const std::vector<Location>& broken);

}  // namespace hmc::motion::planning
