// "0x0000ABCD": how the emulator's messages write an address or a register value. Included by
// .cpp files only.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace hmc::emu {

inline std::string hex32(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

}  // namespace hmc::emu
