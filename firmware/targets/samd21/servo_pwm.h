// ServoPwm on the SAMD21: TCC0 in single-slope PWM at 50 Hz, counting at 3 MHz (48 MHz / 16,
// 60 000 counts per 20 ms period, 1/3 µs per count), one compare channel per servo (board.h).
// A released servo's pin is taken back from TCC0 and held low, so it gets no pulse at all; a
// pulse change on a running servo goes through the buffered compare and takes effect at the
// next period, never mid-pulse.
//
// Starting a released servo: the pin is handed to TCC0 only where TCC0's output is low and stays
// low until the next period begins, so the first pulse is whole. In single-slope PWM the output
// goes high when a period starts and low at the compare match (SAMD21 datasheet, TCC,
// "Single-Slope PWM Generation"); a pin switched over mid-pulse would give a short first pulse,
// and a compare value written below the counter does not match until the next period, so a pin
// switched over in the period of that write could even give a pulse of most of 20 ms. Hence:
// the compare value is written, one period start is awaited (OVF), and the pin is switched once
// the counter has passed the compare value and is not near the period's end. service() does it
// from the main loop (within ≤ 22.5 ms of set_pulse), without blocking.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class ServoPwm final : public hal::ServoPwm {
 public:
  void init();  // counter running, both servos released

  void set_pulse(uint8_t servo, uint16_t pulse_us) override;
  void release(uint8_t servo) override;
  // Main loop: hands a started servo's pin to TCC0 once that is safe (above).
  void service();

 private:
  bool running_[2] = {false, false};    // the pin is TCC0's
  bool starting_[2] = {false, false};   // set_pulse() on a released servo, pin not handed over yet
  bool period_seen_[2] = {false, false};  // a period started since the compare was written
  uint32_t counts_[2] = {0, 0};         // the compare value of a starting servo
};

}  // namespace hmc::samd21
