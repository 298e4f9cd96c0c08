// The bootloader's memory map without the CPU (bare_chip.h).
#include "bare_chip.h"

#include <cstdio>

namespace hmc::emu {
namespace {

std::string hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

bool in(uint32_t address, uint32_t base, uint32_t size) { return address >= base && address - base < size; }

}  // namespace

BareChip::BareChip()
    : nvm_([this](const std::string& v) { violations_.push_back(v); }), ram_(kRamSize, 0) {}

std::vector<std::string> BareChip::take_violations() {
  std::vector<std::string> taken;
  taken.swap(violations_);
  return taken;
}

bool BareChip::read(uint32_t address, unsigned size, uint32_t& value, std::string& error) {
  value = 0;
  if (address % size != 0) {
    error = "unaligned " + std::to_string(size) + "-byte read at " + hex(address);
    return false;
  }
  if (Nvmctrl::in_nvm_space(address)) {
    value = nvm_.read_memory(address, size);
    return true;
  }
  if (in(address, kRamBase, kRamSize)) {
    for (unsigned i = 0; i < size; ++i) value |= static_cast<uint32_t>(ram_[address - kRamBase + i]) << (8 * i);
    return true;
  }
  if (in(address, Nvmctrl::kBase, 0x24)) {
    value = nvm_.read(address - Nvmctrl::kBase, size);
    return true;
  }
  const uint32_t word = address & ~3u;
  const uint32_t shift = 8 * (address & 3u);
  const uint32_t mask = size == 4 ? 0xFFFFFFFFu : (1u << (8 * size)) - 1;
  if (word == kDsuDid) {
    value = (kDeviceId >> shift) & mask;
    return true;
  }
  if (word == kCpuidAddress) {
    value = (kCpuid >> shift) & mask;
    return true;
  }
  if (word == kAircr) {  // VECTKEYSTAT reads 0xFA05 (ARMv6-M, AIRCR)
    value = (0xFA050000u >> shift) & mask;
    return true;
  }
  error = "read of " + hex(address) + ": nothing there in the bootloader's memory map";
  return false;
}

bool BareChip::write(uint32_t address, uint32_t value, unsigned size, std::string& error) {
  if (address % size != 0) {
    error = "unaligned " + std::to_string(size) + "-byte write at " + hex(address);
    return false;
  }
  if (Nvmctrl::in_nvm_space(address)) {
    nvm_.write_memory(address, value, size);
    return true;
  }
  if (in(address, kRamBase, kRamSize)) {
    for (unsigned i = 0; i < size; ++i) ram_[address - kRamBase + i] = static_cast<uint8_t>(value >> (8 * i));
    return true;
  }
  if (in(address, Nvmctrl::kBase, 0x24)) {
    nvm_.write(address - Nvmctrl::kBase, value, size);
    return true;
  }
  if (address == kAircr && size == 4) {
    // ARMv6-M AIRCR: a write takes effect only with VECTKEY 0x05FA in bits 31:16; SYSRESETREQ
    // (bit 2) asks for a system reset.
    if ((value >> 16) == 0x05FA && (value & (1u << 2)) != 0) reset_requested_ = true;
    return true;
  }
  error = "write of " + hex(value) + " to " + hex(address) + ": nothing writable there in the bootloader's memory map";
  return false;
}

}  // namespace hmc::emu
