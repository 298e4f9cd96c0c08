// UF2 writer (uf2.h): one block per 256 bytes of the image, in address order.
#include <stdexcept>

#include "uf2.h"

namespace hmc::uf2 {
namespace {

void put32(std::vector<uint8_t>& out, size_t offset, uint32_t value) {
  for (size_t i = 0; i < 4; ++i) out[offset + i] = static_cast<uint8_t>(value >> (8 * i));
}

}  // namespace

std::vector<uint8_t> from_bin(const std::vector<uint8_t>& bin, const Options& options) {
  if (bin.empty()) throw std::invalid_argument("the image is empty");
  const uint64_t blocks = (bin.size() + kPayloadSize - 1) / kPayloadSize;
  if (options.base + blocks * kPayloadSize > 0x100000000ull) {
    throw std::invalid_argument("the image does not fit in the 32-bit address space");
  }
  std::vector<uint8_t> out(blocks * kBlockSize, 0);
  for (uint32_t n = 0; n < blocks; ++n) {
    const size_t block = size_t{n} * kBlockSize;
    put32(out, block + 0, kMagicStart0);
    put32(out, block + 4, kMagicStart1);
    put32(out, block + 8, kFlagFamilyIdPresent);
    put32(out, block + 12, options.base + n * kPayloadSize);
    put32(out, block + 16, kPayloadSize);
    put32(out, block + 20, n);
    put32(out, block + 24, static_cast<uint32_t>(blocks));
    put32(out, block + 28, options.family);
    for (size_t i = 0; i < kPayloadSize; ++i) {
      const size_t at = size_t{n} * kPayloadSize + i;
      out[block + kDataOffset + i] = at < bin.size() ? bin[at] : kPadByte;
    }
    put32(out, block + kBlockSize - 4, kMagicEnd);
  }
  return out;
}

}  // namespace hmc::uf2
