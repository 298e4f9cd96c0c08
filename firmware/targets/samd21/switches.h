// Switches on the SAMD21: the four limit switches and the emergency switch as inputs with
// pull-ups (board.h), each on its own EIC line sensing both edges. The EIC interrupt (priority
// below the step timer) clears its flags and lets main.cpp call Controller::on_switch_change();
// the controller then reads the levels through limit_pressed() / emergency_pressed().
//
// The EIC runs from a 32.768 kHz clock with its majority filter on: a pulse shorter than about
// two clock periods (≈ 60 µs, a spike on a long switch wire) is ignored, and a real edge is seen
// within about 100 µs. The level reads are direct port reads, without that filter.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class Switches final : public hal::Switches {
 public:
  void init();

  bool limit_pressed(uint8_t motor, uint8_t end) const override;
  bool emergency_pressed() const override;

  // The EIC interrupt: clears the flags of every line that fired.
  void take_interrupt();
};

}  // namespace hmc::samd21
