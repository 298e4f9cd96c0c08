// StepPins on the SAMD21: the STEP and DIR lines of drivers 1-3 as GPIO outputs (board.h),
// written through the single-cycle IOBUS port from the step interrupt.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class StepPins final : public hal::StepPins {
 public:
  // Every STEP, DIR and chip-select line an output, driven low (chip select inactive).
  void init();

  void set_dir(uint8_t motor, bool reverse) override;
  void set_step(uint8_t motor, bool high) override;
};

}  // namespace hmc::samd21
