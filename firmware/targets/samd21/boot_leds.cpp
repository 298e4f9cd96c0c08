// BootLeds (boot_leds.h).
#include "boot_leds.h"

#include "board.h"
#include "pins.h"

namespace hmc::samd21 {

void BootLeds::init() {
  pin_output(board::kBootLedLeft, false);
  pin_output(board::kBootLedRight, false);
}

void BootLeds::set(bool left_on, bool right_on) {
  pin_set(board::kBootLedLeft, left_on);
  pin_set(board::kBootLedRight, right_on);
}

}  // namespace hmc::samd21
