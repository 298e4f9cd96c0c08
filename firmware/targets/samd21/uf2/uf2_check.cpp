// UF2 validator (uf2.h). Written apart from the writer: it reads every field back from the
// bytes and compares it with what the format and the image require.
#include <cstdio>

#include "uf2.h"

namespace hmc::uf2 {
namespace {

uint32_t get32(const std::vector<uint8_t>& in, size_t offset) {
  uint32_t value = 0;
  for (size_t i = 0; i < 4; ++i) value |= static_cast<uint32_t>(in[offset + i]) << (8 * i);
  return value;
}

bool fail(std::string& error, size_t block, const char* field, uint32_t got, uint32_t want) {
  char text[160];
  std::snprintf(text, sizeof(text), "block %zu: %s is 0x%08X, expected 0x%08X", block, field,
                static_cast<unsigned>(got), static_cast<unsigned>(want));
  error = text;
  return false;
}

}  // namespace

bool check(const std::vector<uint8_t>& uf2, const std::vector<uint8_t>& bin, const Options& options,
           std::string& error) {
  if (uf2.empty() || uf2.size() % kBlockSize != 0) {
    error = "file size " + std::to_string(uf2.size()) + " is not a positive multiple of 512";
    return false;
  }
  const size_t blocks = uf2.size() / kBlockSize;
  const size_t want_blocks = (bin.size() + kPayloadSize - 1) / kPayloadSize;
  if (blocks != want_blocks) {
    error = std::to_string(blocks) + " blocks for a " + std::to_string(bin.size()) +
            "-byte image, expected " + std::to_string(want_blocks);
    return false;
  }
  for (size_t n = 0; n < blocks; ++n) {
    const size_t b = n * kBlockSize;
    const uint32_t address = options.base + static_cast<uint32_t>(n * kPayloadSize);
    const struct {
      const char* field;
      size_t offset;
      uint32_t want;
    } fields[] = {
        {"magic 0", 0, kMagicStart0},
        {"magic 1", 4, kMagicStart1},
        {"flags", 8, kFlagFamilyIdPresent},
        {"target address", 12, address},
        {"payload size", 16, kPayloadSize},
        {"block number", 20, static_cast<uint32_t>(n)},
        {"number of blocks", 24, static_cast<uint32_t>(blocks)},
        {"family id", 28, options.family},
        {"end magic", kBlockSize - 4, kMagicEnd},
    };
    for (const auto& f : fields) {
      const uint32_t got = get32(uf2, b + f.offset);
      if (got != f.want) return fail(error, n, f.field, got, f.want);
    }
    for (size_t i = 0; i < kPayloadSize; ++i) {
      const size_t at = n * kPayloadSize + i;
      const uint8_t want = at < bin.size() ? bin[at] : kPadByte;
      const uint8_t got = uf2[b + kDataOffset + i];
      if (got != want) return fail(error, n, "payload byte", got, want);
    }
    for (size_t i = kDataOffset + kPayloadSize; i < kBlockSize - 4; ++i) {
      if (uf2[b + i] != 0) return fail(error, n, "data padding", uf2[b + i], 0);
    }
  }
  return true;
}

}  // namespace hmc::uf2
