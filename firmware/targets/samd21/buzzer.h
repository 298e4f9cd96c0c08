// Buzzer on the SAMD21: TC3 in match-frequency mode toggles its WO[0] pin (board.h), giving a
// square wave at the tone's frequency with no CPU work. tone() starts it and returns; service(),
// called by the main loop, silences it once the tone's time is up (read from the step timer's
// clock). A silent buzzer's pin is a GPIO held low.
#pragma once

#include <stdint.h>

#include "core/hal.h"
#include "step_timer.h"

namespace hmc::samd21 {

class Buzzer final : public hal::Buzzer {
 public:
  // The clock is the concrete (final) timer: calls to it are direct, not virtual.
  explicit Buzzer(const StepTimer& clock) : clock_(clock) {}
  void init();

  // hz 0 is a rest: silence for `ms`. A new tone replaces the one playing.
  void tone(uint16_t hz, uint16_t ms) override;
  void service();  // main loop

 private:
  void silence();

  const StepTimer& clock_;
  hal::Ticks stop_at_ = 0;
  bool sounding_ = false;
};

}  // namespace hmc::samd21
