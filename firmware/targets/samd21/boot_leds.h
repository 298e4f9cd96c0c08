// BootLeds on the SAMD21: the two booting LEDs as GPIO outputs (board.h, active high).
#pragma once

#include "core/hal.h"

namespace hmc::samd21 {

class BootLeds final : public hal::BootLeds {
 public:
  void init();  // both off
  void set(bool left_on, bool right_on) override;
};

}  // namespace hmc::samd21
