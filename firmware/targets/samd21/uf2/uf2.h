// UF2, the block format the SAMD21's UF2 bootloader flashes from a USB drive: a file of 512-byte
// blocks, each carrying a slice of the image and the flash address it goes to. Facts from the
// format's README (microsoft/uf2) as HARDWARE.md gives them:
//
//   offset  field (32-bit little endian)
//        0  magic 0x0A324655 ("UF2\n")
//        4  magic 0x9E5D5157
//        8  flags: 0x00002000 = the family id field is present
//       12  target flash address of the payload
//       16  payload size: 256 on the SAMD21
//       20  block number, from 0
//       24  number of blocks in the file
//       28  family id: 0x68ED2B88 for the SAMD21
//   32-507  data: the payload, then zeros
//      508  magic 0x0AB16F30
//
// Host code (the hmc-uf2 tool and its tests); the firmware build compiles it with the host
// compiler, so it depends on the C++17 standard library only.
#pragma once

#include <stdint.h>

#include <string>
#include <vector>

namespace hmc::uf2 {

inline constexpr uint32_t kMagicStart0 = 0x0A324655;
inline constexpr uint32_t kMagicStart1 = 0x9E5D5157;
inline constexpr uint32_t kMagicEnd = 0x0AB16F30;
inline constexpr uint32_t kFlagFamilyIdPresent = 0x00002000;
inline constexpr uint32_t kFamilySamd21 = 0x68ED2B88;
inline constexpr uint32_t kBlockSize = 512;
inline constexpr uint32_t kDataOffset = 32;
inline constexpr uint32_t kDataCapacity = 476;
inline constexpr uint32_t kPayloadSize = 256;
inline constexpr uint32_t kAppBase = 0x2000;  // behind the bootloader (HARDWARE.md)
// Bytes past the end of the image in the last block's payload: the value of erased flash.
inline constexpr uint8_t kPadByte = 0xFF;

struct Options {
  uint32_t base = kAppBase;
  uint32_t family = kFamilySamd21;
};

// The UF2 file for a flat binary image loaded at options.base. Throws std::invalid_argument for
// an empty image or one that does not fit below 4 GiB.
std::vector<uint8_t> from_bin(const std::vector<uint8_t>& bin, const Options& options);

// Checks that `uf2` is exactly the UF2 file of `bin` at options.base: block magics, flags,
// family id, payload size, block numbers and count, consecutive addresses from the base, zero
// padding, and the payload bytes against the image. On failure returns false and says which
// block and field in `error`.
bool check(const std::vector<uint8_t>& uf2, const std::vector<uint8_t>& bin, const Options& options,
           std::string& error);

}  // namespace hmc::uf2
