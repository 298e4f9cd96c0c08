// The SAMD21 watchdog: resets the chip when the main loop stops kicking it for 0.5 s (512
// periods of the 1.024 kHz GCLK2, clocks.h). The step interrupt keeps running when the main loop
// hangs, so the watchdog is what stops a motor whose main loop died.
#pragma once

namespace hmc::samd21 {

void watchdog_start();
// Restarts the timeout; cheap, skipped while the previous kick is still synchronising.
void watchdog_kick();

}  // namespace hmc::samd21
