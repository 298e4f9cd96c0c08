// The SK6812 bit encoding for an SPI data line at 2.4 MHz (HARDWARE.md, SK6812 RGBW): each LED bit
// becomes three SPI bits, 1 → 110 and 0 → 100 (0.83 µs or 0.42 µs high in a 1.25 µs bit), so an
// LED byte is three SPI bytes and an LED (G, R, B, W) twelve. Pure functions, tested on the host
// (sk6812_test.cpp); led_strips.cpp sends what they produce.
#pragma once

#include <stdint.h>

namespace hmc::samd21::sk6812 {

inline constexpr uint32_t kSpiBytesPerLed = 12;

// One LED byte as 24 SPI bits, MSB first, into out[0..2].
constexpr void encode_byte(uint8_t value, uint8_t* out) {
  uint32_t bits = 0;
  for (uint32_t mask = 0x80; mask != 0; mask >>= 1) {
    bits = (bits << 3) | ((value & mask) != 0 ? 0x6u : 0x4u);
  }
  out[0] = static_cast<uint8_t>(bits >> 16);
  out[1] = static_cast<uint8_t>(bits >> 8);
  out[2] = static_cast<uint8_t>(bits);
}

// One LED in the strip's order G, R, B, W into out[0..11].
constexpr void encode_led(uint8_t r, uint8_t g, uint8_t b, uint8_t w, uint8_t* out) {
  encode_byte(g, out);
  encode_byte(r, out + 3);
  encode_byte(b, out + 6);
  encode_byte(w, out + 9);
}

// A colour value at `brightness` of 255 (255 keeps 255; 0 gives 0).
constexpr uint8_t scale(uint8_t value, uint32_t brightness) {
  return static_cast<uint8_t>((value * (brightness + 1u)) >> 8);
}

}  // namespace hmc::samd21::sk6812
