// The host's writing of the frame grammar (frame_grammar.h): canonical frames of checked values,
// written with whole-word copies for the encoders' fast path (docs/performance.md), and their
// checksums. The reading side is frame_grammar.cpp.
#include <cstring>

#include "frame_grammar.h"

namespace hmc::grammar {

namespace {

// Frames are written into FrameText::kRoom bytes: a frame is at most kLineMax of them, and the
// writers store whole words past what they keep. They take and return the write position (a
// local pointer, so the compiler need not fear that the bytes written alias it).

// Numbers are written three digits at a time from two tables of 1 000 four-byte entries, each
// copied whole: kGroups[n] holds n without leading zeros and a '#' ("7#", "42#", "255#"),
// kPaddedGroups[n] three digits and a '#' ("007#"). A field is a number and its '#'.
using Group = std::array<char, 4>;

constexpr std::array<Group, 1000> groups(bool padded) {
  std::array<Group, 1000> out{};
  for (uint32_t n = 0; n < 1000; ++n) {
    const uint32_t digits = padded ? 3 : n < 10 ? 1 : n < 100 ? 2 : 3;
    for (uint32_t i = 0, place = digits == 3 ? 100 : digits == 2 ? 10 : 1; i < digits; ++i, place /= 10) {
      out[n][i] = static_cast<char>('0' + n / place % 10);
    }
    out[n][digits] = '#';
  }
  return out;
}
constexpr auto kGroups = groups(false);
constexpr auto kPaddedGroups = groups(true);

// The bytes of kGroups[n]: its digits and the '#'.
inline uint32_t group_size(uint32_t n) { return 2u + (n >= 10 ? 1u : 0u) + (n >= 100 ? 1u : 0u); }

// n and a '#'. Writes four bytes past the position it returns at most.
inline char* write_field(char* w, uint32_t n) {
  if (n < 1000) {  // most fields
    std::memcpy(w, kGroups[n].data(), 4);
    return w + group_size(n);
  }
  uint32_t low[3];  // the groups after the first, last one first (n < 2^32 has at most four)
  uint32_t count = 0;
  for (; n >= 1000; n /= 1000) low[count++] = n % 1000;
  std::memcpy(w, kGroups[n].data(), 4);
  w += group_size(n) - 1;  // the next group overwrites the '#'
  while (count > 0) {
    std::memcpy(w, kPaddedGroups[low[--count]].data(), 4);
    w += 3;
  }
  return w + 1;
}

// A CRC-16 as the checksum field holds it, kCrcDigits = 5 digits zero-padded, and a '#'.
inline char* write_crc_field(char* w, uint32_t crc) {
  static_assert(proto::kCrcDigits == 5, "two digits, then a padded group of three");
  std::memcpy(w, kPaddedGroups[crc / 1000].data() + 1, 2);
  std::memcpy(w + 2, kPaddedGroups[crc % 1000].data(), 4);
  return w + 6;
}

// The head of the frame through the '#' before its first value (or checksum), then the values;
// `sum` gets the seed's checksum on the way.
char* write_head(char* w, const Shape& shape, const uint32_t* values, uint32_t& sum, uint32_t& outside) {
  std::memcpy(w, shape.head.data(), shape.head.size());
  w += shape.head_size;
  uint32_t total = 0;
  uint32_t misses = 0;
  for (uint32_t i = 0; i < shape.value_count; ++i) {
    w = write_field(w, values[i]);
    total += values[i];
    misses |= outside_own_range(shape, i, values[i]);
  }
  sum = total & 0xFFu;
  outside = misses;
  return w;
}

}  // namespace

uint32_t checksum_of(const Shape& shape, const uint32_t* values, proto::ChecksumMode mode) {
  char bytes[FrameText::kRoom];
  uint32_t sum = 0, outside = 0;
  const char* end = write_head(bytes, shape, values, sum, outside);
  return mode == proto::ChecksumMode::kCrc16 ? crc_of(std::string_view(bytes, static_cast<std::size_t>(end - bytes)))
                                              : sum;
}

std::string crc_text(uint32_t crc) {
  char field[8];
  return std::string(field, static_cast<std::size_t>(write_crc_field(field, crc) - field - 1));
}

char* write_frame_bytes(char* w, const Shape& shape, const uint32_t* values, proto::ChecksumMode mode,
                        uint32_t& outside) {
  char* const first = w;
  uint32_t sum = 0;
  w = write_head(w, shape, values, sum, outside);
  w = mode == proto::ChecksumMode::kCrc16
          ? write_crc_field(w, crc_of(std::string_view(first, static_cast<std::size_t>(w - first))))
          : write_field(w, sum);
  std::memcpy(w, kEnd.data(), kEnd.size());
  return w + kEnd.size();
}

std::string write_frame(const Shape& shape, const uint32_t* values, proto::ChecksumMode mode) {
  char bytes[FrameText::kRoom];
  uint32_t outside = 0;
  return std::string(bytes, write_frame_bytes(bytes, shape, values, mode, outside));
}

}  // namespace hmc::grammar
