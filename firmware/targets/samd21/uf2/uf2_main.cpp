// hmc-uf2: converts a firmware .bin to UF2 for the SAMD21 bootloader's USB drive, and checks a
// UF2 file against its .bin (the firmware build does both for hmc-firmware.uf2).
//
//   hmc-uf2 convert IMAGE.bin OUT.uf2 [--base ADDRESS] [--family ID]
//   hmc-uf2 check FILE.uf2 IMAGE.bin [--base ADDRESS] [--family ID]
//
// ADDRESS defaults to 0x2000 (behind the bootloader), ID to 0x68ED2B88 (SAMD21). Exit status:
// 0 done, 1 the check failed or a file could not be read or written, 2 bad usage.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "uf2.h"

namespace {

constexpr const char* kUsage =
    "usage: hmc-uf2 convert IMAGE.bin OUT.uf2 [--base ADDRESS] [--family ID]\n"
    "       hmc-uf2 check FILE.uf2 IMAGE.bin [--base ADDRESS] [--family ID]\n";

bool read_file(const char* path, std::vector<uint8_t>& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

bool write_file(const char* path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(out);
}

bool parse_u32(const char* text, uint32_t& value) {
  char* end = nullptr;
  const unsigned long long parsed = std::strtoull(text, &end, 0);
  if (end == text || *end != '\0' || parsed > 0xFFFFFFFFull) return false;
  value = static_cast<uint32_t>(parsed);
  return true;
}

int usage() {
  std::fputs(kUsage, stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) return usage();
  const std::string command = argv[1];
  hmc::uf2::Options options;
  for (int i = 4; i < argc; i += 2) {
    if (i + 1 >= argc) return usage();
    uint32_t* target = std::strcmp(argv[i], "--base") == 0     ? &options.base
                       : std::strcmp(argv[i], "--family") == 0 ? &options.family
                                                               : nullptr;
    if (target == nullptr || !parse_u32(argv[i + 1], *target)) return usage();
  }
  try {
    if (command == "convert") {
      std::vector<uint8_t> bin;
      if (!read_file(argv[2], bin)) {
        std::fprintf(stderr, "hmc-uf2: cannot read %s\n", argv[2]);
        return 1;
      }
      const std::vector<uint8_t> uf2 = hmc::uf2::from_bin(bin, options);
      if (!write_file(argv[3], uf2)) {
        std::fprintf(stderr, "hmc-uf2: cannot write %s\n", argv[3]);
        return 1;
      }
      std::printf("hmc-uf2: %s: %zu blocks, 0x%08X-0x%08X, family 0x%08X\n", argv[3],
                  uf2.size() / hmc::uf2::kBlockSize, static_cast<unsigned>(options.base),
                  static_cast<unsigned>(options.base + bin.size() - 1),
                  static_cast<unsigned>(options.family));
      return 0;
    }
    if (command == "check") {
      std::vector<uint8_t> uf2;
      std::vector<uint8_t> bin;
      if (!read_file(argv[2], uf2) || !read_file(argv[3], bin)) {
        std::fprintf(stderr, "hmc-uf2: cannot read %s or %s\n", argv[2], argv[3]);
        return 1;
      }
      std::string error;
      if (!hmc::uf2::check(uf2, bin, options, error)) {
        std::fprintf(stderr, "hmc-uf2: %s does not match %s: %s\n", argv[2], argv[3], error.c_str());
        return 1;
      }
      std::printf("hmc-uf2: %s matches %s (%zu blocks)\n", argv[2], argv[3],
                  uf2.size() / hmc::uf2::kBlockSize);
      return 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hmc-uf2: %s\n", e.what());
    return 1;
  }
  return usage();
}
