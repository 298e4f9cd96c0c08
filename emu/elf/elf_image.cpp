// ElfImage (elf_image.h). Layout: the System V ABI's ELF header, program and section headers
// (ELF32, little-endian); symbols from .symtab with STT_FUNC type.
#include "elf_image.h"

#include <cxxabi.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

namespace hmc::emu {
namespace {

constexpr uint16_t kMachineArm = 40;
constexpr uint32_t kPtLoad = 1;
constexpr uint32_t kShtSymtab = 2;
constexpr uint8_t kSttFunc = 2;

uint32_t u32(const std::vector<uint8_t>& b, size_t at) {
  return uint32_t{b[at]} | uint32_t{b[at + 1]} << 8 | uint32_t{b[at + 2]} << 16 |
         uint32_t{b[at + 3]} << 24;
}
uint16_t u16(const std::vector<uint8_t>& b, size_t at) {
  return static_cast<uint16_t>(b[at] | b[at + 1] << 8);
}

}  // namespace

uint32_t ElfImage::lowest_address() const {
  uint32_t lowest = UINT32_MAX;
  for (const Segment& s : segments) lowest = s.address < lowest ? s.address : lowest;
  return lowest;
}

std::vector<uint32_t> ElfImage::functions_named(const std::string& name) const {
  std::vector<uint32_t> out;
  for (const auto& [address, function] : functions) {
    int status = 0;
    char* readable = abi::__cxa_demangle(function.first.c_str(), nullptr, nullptr, &status);
    const std::string demangled = status == 0 && readable != nullptr ? readable : function.first;
    std::free(readable);
    if (function.first == name || demangled == name || demangled.substr(0, demangled.find('(')) == name) {
      out.push_back(address);
    }
  }
  return out;
}

std::string ElfImage::function_at(uint32_t address) const {
  address &= ~1u;
  auto it = functions.upper_bound(address);
  if (it == functions.begin()) return "?";
  --it;
  const uint32_t start = it->first;
  if (address - start >= (it->second.second == 0 ? 1u : it->second.second)) return "?";
  char offset[16];
  std::snprintf(offset, sizeof offset, "+0x%X", address - start);
  int status = 0;
  char* readable = abi::__cxa_demangle(it->second.first.c_str(), nullptr, nullptr, &status);
  std::string name = status == 0 && readable != nullptr ? readable : it->second.first;
  std::free(readable);
  return name + offset;
}

bool load_elf(const std::string& path, ElfImage& image, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = "cannot read '" + path + "': " + std::strerror(errno);
    return false;
  }
  const std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)),
                               std::istreambuf_iterator<char>());
  const auto bad = [&](const std::string& why) {
    error = "'" + path + "' is not a firmware image: " + why;
    return false;
  };
  if (b.size() < 52 || std::memcmp(b.data(), "\x7f" "ELF", 4) != 0) return bad("no ELF header");
  if (b[4] != 1 || b[5] != 1) return bad("not a 32-bit little-endian ELF");
  if (u16(b, 18) != kMachineArm) return bad("not an ARM ELF (machine " + std::to_string(u16(b, 18)) + ")");
  image = ElfImage{};
  image.entry = u32(b, 24);
  const uint32_t phoff = u32(b, 28), shoff = u32(b, 32);
  const uint16_t phentsize = u16(b, 42), phnum = u16(b, 44);
  const uint16_t shentsize = u16(b, 46), shnum = u16(b, 48);
  if (uint64_t{phoff} + uint64_t{phnum} * phentsize > b.size() || phentsize < 32) {
    return bad("program headers outside the file");
  }
  for (uint16_t i = 0; i < phnum; ++i) {
    const size_t h = phoff + size_t{i} * phentsize;
    if (u32(b, h) != kPtLoad || u32(b, h + 16) == 0) continue;
    const uint32_t offset = u32(b, h + 4), paddr = u32(b, h + 12), filesz = u32(b, h + 16);
    if (uint64_t{offset} + filesz > b.size()) return bad("a segment outside the file");
    image.segments.push_back(
        Segment{paddr, std::vector<uint8_t>(b.begin() + offset, b.begin() + offset + filesz)});
  }
  if (image.segments.empty()) return bad("no loadable bytes");
  if (shoff != 0 && shentsize >= 40 && uint64_t{shoff} + uint64_t{shnum} * shentsize <= b.size()) {
    for (uint16_t i = 0; i < shnum; ++i) {
      const size_t h = shoff + size_t{i} * shentsize;
      if (u32(b, h + 4) != kShtSymtab) continue;
      const uint32_t off = u32(b, h + 16), size = u32(b, h + 20), link = u32(b, h + 24);
      if (link >= shnum || uint64_t{off} + size > b.size()) continue;
      const size_t sh = shoff + size_t{link} * shentsize;
      const uint32_t stroff = u32(b, sh + 16), strsize = u32(b, sh + 20);
      if (uint64_t{stroff} + strsize > b.size()) continue;
      for (uint32_t s = 0; s + 16 <= size; s += 16) {
        const uint32_t name = u32(b, off + s), value = u32(b, off + s + 4);
        if ((b[off + s + 12] & 0xF) != kSttFunc || name >= strsize) continue;
        const char* text = reinterpret_cast<const char*>(&b[stroff + name]);
        image.functions[value & ~1u] = {std::string(text, strnlen(text, strsize - name)),
                                        u32(b, off + s + 8)};
      }
    }
  }
  image.lines = std::make_shared<const SourceLines>(path);
  return true;
}

}  // namespace hmc::emu
