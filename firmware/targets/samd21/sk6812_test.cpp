// Tests of the SK6812 SPI encoding (sk6812.h): bit patterns written out by hand from the
// 1 → 110, 0 → 100 rule, the G R B W order, and the brightness scale.
#include "sk6812.h"

#include <catch2/catch.hpp>

#include <array>

namespace sk = hmc::samd21::sk6812;

namespace {

std::array<uint8_t, 3> byte(uint8_t value) {
  std::array<uint8_t, 3> out{};
  sk::encode_byte(value, out.data());
  return out;
}

}  // namespace

TEST_CASE("each LED bit becomes three SPI bits, MSB first") {
  // 0x00: 100 100 100 100 100 100 100 100 = 1001 0010 0100 1001 0010 0100
  CHECK(byte(0x00) == std::array<uint8_t, 3>{0x92, 0x49, 0x24});
  // 0xFF: 110 ×8 = 1101 1011 0110 1101 1011 0110
  CHECK(byte(0xFF) == std::array<uint8_t, 3>{0xDB, 0x6D, 0xB6});
  // 0x80: 110 then 100 ×7 = 1101 0010 0100 1001 0010 0100
  CHECK(byte(0x80) == std::array<uint8_t, 3>{0xD2, 0x49, 0x24});
  // 0x01: 100 ×7 then 110 = 1001 0010 0100 1001 0010 0110
  CHECK(byte(0x01) == std::array<uint8_t, 3>{0x92, 0x49, 0x26});
}

TEST_CASE("every SPI bit triple starts high and ends low") {
  for (uint32_t v = 0; v < 256; ++v) {
    const auto b = byte(static_cast<uint8_t>(v));
    const uint32_t bits = static_cast<uint32_t>(b[0]) << 16 | static_cast<uint32_t>(b[1]) << 8 | b[2];
    for (int i = 7; i >= 0; --i) {
      const uint32_t triple = (bits >> (3 * i)) & 7u;
      CHECK((triple == 4u || triple == 6u));
      CHECK(((triple & 2u) != 0) == ((v >> i) & 1u));
    }
  }
}

TEST_CASE("an LED is sent green, red, blue, white") {
  std::array<uint8_t, 12> led{};
  sk::encode_led(0xFF, 0x00, 0x80, 0x01, led.data());
  const std::array<uint8_t, 12> want = {0x92, 0x49, 0x24,   // G 0x00
                                        0xDB, 0x6D, 0xB6,   // R 0xFF
                                        0xD2, 0x49, 0x24,   // B 0x80
                                        0x92, 0x49, 0x26};  // W 0x01
  CHECK(led == want);
}

TEST_CASE("brightness scales a colour value") {
  CHECK(sk::scale(255, 255) == 255);
  CHECK(sk::scale(0, 255) == 0);
  CHECK(sk::scale(255, 100) == 100);  // the seed's brightness: full colour becomes 100
  CHECK(sk::scale(128, 100) == 50);
  CHECK(sk::scale(200, 0) == 0);
}
