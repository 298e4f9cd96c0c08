// StepPins (step_pins.h). DIR high means reverse; a driver whose motor turns the other way is
// corrected in the driver (CTRL.RDIR), not here.
#include "step_pins.h"

#include "board.h"
#include "pins.h"

namespace hmc::samd21 {

void StepPins::init() {
  for (const board::DriverPins& driver : board::kDrivers) {
    pin_output(driver.step, false);
    pin_output(driver.dir, false);
    pin_output(driver.cs, false);
  }
}

void StepPins::set_dir(uint8_t motor, bool reverse) {
  if (motor < 1 || motor > 3) return;
  pin_set(board::kDrivers[motor - 1].dir, reverse);
}

void StepPins::set_step(uint8_t motor, bool high) {
  if (motor < 1 || motor > 3) return;
  pin_set(board::kDrivers[motor - 1].step, high);
}

}  // namespace hmc::samd21
