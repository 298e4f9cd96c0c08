// LedStrips on the SAMD21: each SK6812 RGBW strip is fed by its own SERCOM as an SPI master at
// 2.4 MHz, three SPI bits per LED bit (sk6812.h), moved by DMA so the CPU and the step interrupt are never held up (HARDWARE.md, SK6812).
//
// A strip shows one colour (hal::LedStrips). set_color() records it and, when the strip is idle,
// encodes the frame (90 LEDs × 32 bits, G R B W, MSB first, scaled by the board's brightness)
// and starts the DMA; a colour set while a frame is still going out is sent by service() as
// soon as the strip is free (the main loop calls it), so the newest colour always wins.
// A frame is 1080 data bytes (3.6 ms) plus 90 zero bytes (300 µs low: the latch, ≥ 80 µs).
// Every encoded bit ends low, and the data pin stays with the SERCOM, whose output holds the
// last bit between frames.
#pragma once

#include <stdint.h>

#include "board.h"
#include "core/hal.h"

namespace hmc::samd21 {

class LedStrips final : public hal::LedStrips {
 public:
  void init();  // SERCOMs and DMA ready, both strips sent dark

  void set_color(uint8_t strip, uint8_t r, uint8_t g, uint8_t b, uint8_t w) override;
  // Main loop: starts a waiting frame on a strip that finished its last one.
  void service();

  static constexpr uint32_t kDataBytes = board::kLedsPerStrip * 32u * 3u / 8u;  // 1080
  static constexpr uint32_t kLatchBytes = 90;                                 // 300 µs
  static constexpr uint32_t kFrameBytes = kDataBytes + kLatchBytes;

 private:
  struct Strip {
    uint8_t rgbw[4];  // scaled by the board's brightness
    bool waiting;  // a colour not yet sent
  };
  void start(uint32_t index);

  Strip strips_[2] = {};
  // The frames themselves (2 × 1170 bytes) are zero-initialised statics of led_strips.cpp, in
  // .bss: the board has one pair of strips, so one LedStrips.
};

}  // namespace hmc::samd21
