// ServoPwm on the SAMD21: TCC0 in single-slope PWM at 50 Hz, counting at 3 MHz (48 MHz / 16,
// 60 000 counts per 20 ms period, 1/3 µs per count), one compare channel per servo (board.h).
// A released servo's pin is taken back from TCC0 and held low, so it gets no pulse at all; a
// pulse change on a running servo goes through the buffered compare and takes effect at the
// next period, never mid-pulse.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class ServoPwm final : public hal::ServoPwm {
 public:
  void init();  // counter running, both servos released

  void set_pulse(uint8_t servo, uint16_t pulse_us) override;
  void release(uint8_t servo) override;

 private:
  bool running_[2] = {false, false};
};

}  // namespace hmc::samd21
