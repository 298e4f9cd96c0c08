// CRC-16 of protocol v2's checksum mode (docs/protocol.md "CRC-16 mode"): polynomial 0x1021,
// initial value 0xFFFF, no reflection, no final XOR. "123456789" gives 0x29B1. Bitwise, no
// table: a frame is at most 128 bytes and the board has flash to spare, not RAM to waste.
// Header-only and freestanding, for the firmware, the host codec and the benchmarks alike.
#pragma once

#include <stdint.h>

namespace hmc::proto {

inline constexpr uint16_t kCrcInitial = 0xFFFF;

constexpr uint16_t crc16_update(uint16_t crc, uint8_t byte) {
  crc = static_cast<uint16_t>(crc ^ (static_cast<uint16_t>(byte) << 8));
  for (int bit = 0; bit < 8; ++bit) {
    const uint32_t shifted = static_cast<uint32_t>(crc) << 1;
    crc = static_cast<uint16_t>((crc & 0x8000u) != 0 ? shifted ^ 0x1021u : shifted);
  }
  return crc;
}

constexpr uint16_t crc16(const uint8_t* bytes, uint32_t count, uint16_t crc = kCrcInitial) {
  for (uint32_t i = 0; i < count; ++i) crc = crc16_update(crc, bytes[i]);
  return crc;
}

constexpr uint16_t crc16_of_text(const char* text) {
  uint16_t crc = kCrcInitial;
  while (*text != '\0') crc = crc16_update(crc, static_cast<uint8_t>(*text++));
  return crc;
}
static_assert(crc16_of_text("123456789") == 0x29B1, "CRC-16 check value");

// How the checksum field of a frame is computed: the seed's sum of the values mod 256, or the
// CRC-16 of the frame's bytes from the 'S' of STX through the '#' before the checksum field.
enum class ChecksumMode : uint8_t { kSum = 0, kCrc16 = 1 };

}  // namespace hmc::proto
