// The firmware image as the emulator loads it: an ARM ELF32's loadable bytes at their load
// addresses (what objcopy puts in the .bin), and its function symbols, to name where the program
// counter is. Errors are values: a missing file, a non-ARM or non-ELF32 file, no loadable bytes.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "source_lines.h"

namespace hmc::emu {

struct Segment {
  uint32_t address;  // load (physical) address
  std::vector<uint8_t> bytes;
};

struct ElfImage {
  std::vector<Segment> segments;
  // Function symbols by start address: name and size.
  std::map<uint32_t, std::pair<std::string, uint32_t>> functions;
  uint32_t entry = 0;
  // The DWARF line tables, when the ELF has them (source_lines.h).
  std::shared_ptr<const SourceLines> lines;

  uint32_t lowest_address() const;
  // "name+0x12" for a code address, or "?" when no function holds it.
  std::string function_at(uint32_t address) const;
  // The start addresses of the functions called `name`: the symbol as written, or demangled
  // with or without its parameter list ("hmc::fw::Controller::poll").
  std::vector<uint32_t> functions_named(const std::string& name) const;
  // "/src/firmware/core/controller.cpp:95", or "" without line tables for the address.
  std::string source_line(uint32_t address) const { return lines ? lines->at(address) : ""; }
};

// Loads `path`; on failure returns false with `error` saying what and where.
bool load_elf(const std::string& path, ElfImage& image, std::string& error);

}  // namespace hmc::emu
