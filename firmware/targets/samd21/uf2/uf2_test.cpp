// Tests of the UF2 writer and validator (uf2.h): a known image converted and checked field by
// field, the header bytes pinned to the format's published values, and every kind of damage the
// validator must catch.
#include <catch2/catch.hpp>

#include <stdint.h>

#include <string>
#include <vector>

#include "uf2.h"

namespace {

using hmc::uf2::Options;

// A known 1000-byte image: a fixed linear congruential sequence.
std::vector<uint8_t> known_image(size_t size = 1000) {
  std::vector<uint8_t> bin(size);
  uint32_t x = 12345;
  for (auto& byte : bin) {
    x = x * 1103515245u + 12345u;
    byte = static_cast<uint8_t>(x >> 16);
  }
  return bin;
}

uint32_t get32(const std::vector<uint8_t>& v, size_t offset) {
  return static_cast<uint32_t>(v[offset]) | static_cast<uint32_t>(v[offset + 1]) << 8 |
         static_cast<uint32_t>(v[offset + 2]) << 16 | static_cast<uint32_t>(v[offset + 3]) << 24;
}

void put32(std::vector<uint8_t>& v, size_t offset, uint32_t value) {
  for (size_t i = 0; i < 4; ++i) v[offset + i] = static_cast<uint8_t>(value >> (8 * i));
}

std::string check_error(const std::vector<uint8_t>& uf2, const std::vector<uint8_t>& bin,
                        const Options& options = Options{}) {
  std::string error;
  return hmc::uf2::check(uf2, bin, options, error) ? std::string() : error;
}

}  // namespace

TEST_CASE("a known image becomes one block per 256 bytes at 0x2000 and validates") {
  const auto bin = known_image();
  const auto uf2 = hmc::uf2::from_bin(bin, Options{});
  REQUIRE(uf2.size() == 4 * 512);
  CHECK(check_error(uf2, bin).empty());
  for (size_t n = 0; n < 4; ++n) {
    const size_t b = n * 512;
    CHECK(get32(uf2, b + 12) == 0x2000 + 256 * n);
    CHECK(get32(uf2, b + 20) == n);
    CHECK(get32(uf2, b + 24) == 4);
  }
  // The payload is the image, in order; the last block is padded with 0xFF.
  std::vector<uint8_t> payload;
  for (size_t n = 0; n < 4; ++n) {
    payload.insert(payload.end(), uf2.begin() + static_cast<long>(n * 512 + 32),
                   uf2.begin() + static_cast<long>(n * 512 + 32 + 256));
  }
  CHECK(std::vector<uint8_t>(payload.begin(), payload.begin() + 1000) == bin);
  CHECK(std::vector<uint8_t>(payload.begin() + 1000, payload.end()) == std::vector<uint8_t>(24, 0xFF));
}

TEST_CASE("block header bytes are the format's published values") {
  const auto uf2 = hmc::uf2::from_bin(known_image(), Options{});
  const std::vector<uint8_t> head(uf2.begin(), uf2.begin() + 32);
  const std::vector<uint8_t> want = {
      0x55, 0x46, 0x32, 0x0A,  // "UF2\n" = 0x0A324655
      0x57, 0x51, 0x5D, 0x9E,  // 0x9E5D5157
      0x00, 0x20, 0x00, 0x00,  // flags: family id present
      0x00, 0x20, 0x00, 0x00,  // target address 0x2000
      0x00, 0x01, 0x00, 0x00,  // 256 payload bytes
      0x00, 0x00, 0x00, 0x00,  // block 0
      0x04, 0x00, 0x00, 0x00,  // of 4
      0x88, 0x2B, 0xED, 0x68,  // SAMD21 family 0x68ED2B88
  };
  CHECK(head == want);
  const std::vector<uint8_t> tail(uf2.begin() + 508, uf2.begin() + 512);
  CHECK(tail == std::vector<uint8_t>{0x30, 0x6F, 0xB1, 0x0A});
  for (size_t i = 32 + 256; i < 508; ++i) CHECK(uf2[i] == 0);
}

TEST_CASE("an image of whole blocks needs no padding, and another base is honoured") {
  const auto bin = known_image(512);
  Options at_zero;
  at_zero.base = 0;
  const auto uf2 = hmc::uf2::from_bin(bin, at_zero);
  REQUIRE(uf2.size() == 2 * 512);
  CHECK(get32(uf2, 12) == 0);
  CHECK(get32(uf2, 512 + 12) == 256);
  CHECK(check_error(uf2, bin, at_zero).empty());
  CHECK(check_error(uf2, bin) == "block 0: target address is 0x00000000, expected 0x00002000");
}

TEST_CASE("the validator catches each damaged field") {
  const auto bin = known_image();
  const auto good = hmc::uf2::from_bin(bin, Options{});
  struct Damage {
    size_t offset;
    uint32_t value;
    const char* message;
  };
  const Damage cases[] = {
      {512 + 0, 0x0A324656, "block 1: magic 0"},
      {512 + 4, 0, "block 1: magic 1"},
      {8, 0, "block 0: flags"},
      {3 * 512 + 12, 0x2400, "block 3: target address"},
      {16, 476, "block 0: payload size"},
      {2 * 512 + 20, 3, "block 2: block number"},
      {24, 5, "block 0: number of blocks"},
      {28, 0x1851780A, "block 0: family id"},
      {508, 0, "block 0: end magic"},
      {2 * 512 + 400, 1, "block 2: data padding"},
  };
  for (const Damage& d : cases) {
    auto uf2 = good;
    put32(uf2, d.offset, d.value);
    const std::string error = check_error(uf2, bin);
    INFO(d.message);
    CHECK(error.rfind(d.message, 0) == 0);
  }
}

TEST_CASE("the validator compares the payload with the image") {
  auto bin = known_image();
  const auto uf2 = hmc::uf2::from_bin(bin, Options{});
  bin[700] = static_cast<uint8_t>(bin[700] ^ 0x01);
  CHECK(check_error(uf2, bin).rfind("block 2: payload byte", 0) == 0);
  bin[700] = static_cast<uint8_t>(bin[700] ^ 0x01);
  auto padded = uf2;
  padded[3 * 512 + 32 + 250] = 0x00;  // the 0xFF pad past the image's end
  CHECK(check_error(padded, bin).rfind("block 3: payload byte", 0) == 0);
  auto longer = bin;
  longer.push_back(0xFF);  // still four blocks, but the image claims the first pad byte
  CHECK(check_error(uf2, longer).empty());
  longer.resize(1025, 0xFF);  // five blocks expected
  CHECK(check_error(uf2, longer) == "4 blocks for a 1025-byte image, expected 5");
}

TEST_CASE("the validator rejects a truncated file, and the writer an empty image") {
  const auto bin = known_image();
  auto uf2 = hmc::uf2::from_bin(bin, Options{});
  uf2.resize(uf2.size() - 1);
  CHECK(check_error(uf2, bin) == "file size 2047 is not a positive multiple of 512");
  CHECK(check_error({}, bin) == "file size 0 is not a positive multiple of 512");
  CHECK_THROWS(hmc::uf2::from_bin({}, Options{}));
}
