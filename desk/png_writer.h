// write_png: an RGB image to a PNG file (the screenshots of the test mode), with zlib.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hmc::desk {

// `rgb` holds height rows of width pixels, 3 bytes each, top row first. False when the file
// cannot be written.
bool write_png(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

}  // namespace hmc::desk
