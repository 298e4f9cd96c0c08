// SourceLines (source_lines.h): libdw's compilation unit for an address, then the line table's
// row for it.
#include "source_lines.h"

#include <elfutils/libdw.h>
#include <fcntl.h>
#include <unistd.h>

#include <filesystem>

namespace hmc::emu {

SourceLines::SourceLines(const std::string& path) {
  fd_ = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) return;
  dwarf_ = dwarf_begin(fd_, DWARF_C_READ);  // nullptr: no DWARF in the file
}

SourceLines::~SourceLines() {
  if (dwarf_ != nullptr) dwarf_end(dwarf_);
  if (fd_ >= 0) close(fd_);
}

std::string SourceLines::at(uint32_t address) const {
  if (dwarf_ == nullptr) return "";
  const Dwarf_Addr pc = address & ~1u;  // a Thumb address's bit 0 is not part of it
  Dwarf_Die unit;
  if (dwarf_addrdie(dwarf_, pc, &unit) == nullptr) return "";
  Dwarf_Line* line = dwarf_getsrc_die(&unit, pc);
  if (line == nullptr) return "";
  const char* file = dwarf_linesrc(line, nullptr, nullptr);
  int number = 0;
  if (file == nullptr || dwarf_lineno(line, &number) != 0) return "";
  return std::filesystem::path(file).lexically_normal().string() + ":" + std::to_string(number);
}

}  // namespace hmc::emu
