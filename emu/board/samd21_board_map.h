// The firmware's pin map, read by the emulator so the two never disagree: board.h is plain
// constexpr data (it includes only <stdint.h> and regs_port.h).
#pragma once

#include "../../firmware/targets/samd21/board.h"
