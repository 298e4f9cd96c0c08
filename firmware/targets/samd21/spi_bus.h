// SpiBus on the SAMD21: SERCOM4 as SPI master to the three DRV8711 drivers (board.h), mode 0,
// MSB first, 500 kHz. transfer16() raises the chip's select (active high), clocks two bytes,
// waits for the second to come back and drops the select, which latches a write. Polled: it is
// called from the main loop only, a few times at boot and on a microstep change (32 µs each).
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class SpiBus final : public hal::SpiBus {
 public:
  void init();  // the chip selects are already outputs, low (StepPins::init)
  uint16_t transfer16(uint8_t chip, uint16_t word) override;
};

}  // namespace hmc::samd21
