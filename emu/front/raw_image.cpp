// Raw flash images (raw_image.h).
#include "raw_image.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace hmc::emu {
namespace {
constexpr uint32_t kFlashSize = 256u * 1024u;  // SAMD21G18A
}

bool is_raw_image(const std::string& path) {
  return path.size() > 4 && path.compare(path.size() - 4, 4, ".bin") == 0;
}

bool load_raw_image(const std::string& path, uint32_t base, ElfImage& image, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = "cannot read '" + path + "': " + std::strerror(errno);
    return false;
  }
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.empty()) {
    error = "'" + path + "' is empty: no image to run";
    return false;
  }
  if (base >= kFlashSize || bytes.size() > kFlashSize - base) {
    error = "'" + path + "' (" + std::to_string(bytes.size()) + " bytes at " + std::to_string(base) +
            ") does not fit the 256 KB flash";
    return false;
  }
  image = ElfImage{};
  image.segments.push_back(Segment{base, std::move(bytes)});
  return true;
}

}  // namespace hmc::emu
