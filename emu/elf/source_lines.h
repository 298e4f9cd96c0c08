// Source lines of the image's code addresses, from its DWARF line tables (.debug_line, present
// when the firmware was compiled with -g, as the firmware preset does), read with elfutils'
// libdw. An image without them has none, and the emulator names the function alone.
#pragma once

#include <cstdint>
#include <string>

struct Dwarf;

namespace hmc::emu {

class SourceLines {
 public:
  // Reads the line tables of the ELF at `path`; an unreadable file or one without DWARF gives
  // an object that knows no line.
  explicit SourceLines(const std::string& path);
  ~SourceLines();
  SourceLines(const SourceLines&) = delete;
  SourceLines& operator=(const SourceLines&) = delete;

  // "/src/firmware/core/controller.cpp:95" for a code address, or "" when no table covers it.
  std::string at(uint32_t address) const;

 private:
  int fd_ = -1;
  Dwarf* dwarf_ = nullptr;
};

}  // namespace hmc::emu
