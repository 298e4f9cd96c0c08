// The chip in its bootloader, without the CPU (bare_chip.h).
#include "bare_chip.h"

#include "hex.h"

namespace hmc::emu {
namespace {

bool in(uint32_t address, uint32_t base, uint32_t size) { return address >= base && address - base < size; }

}  // namespace

BareChip::BareChip() : chip_(ChipOptions{}), ram_(kRamSize, 0) {}

bool BareChip::peripheral(uint32_t address) const {
  // The regions the chip's bus dispatches: APB bridges A, B, C and the System Control Space.
  return in(address, 0x40000000, 0x10000) || in(address, 0x41000000, 0x10000) ||
         in(address, 0x42000000, 0x10000) || in(address, 0xE000E000, 0x1000);
}

// The chip keeps its first violation; a new one since the last look refuses the access.
bool BareChip::refused(std::string& error) {
  const std::string& message = chip_.violation_message();
  if (message.empty() || message == reported_) return false;
  reported_ = message;
  error = message;
  return true;
}

bool BareChip::read(uint32_t address, unsigned size, uint32_t& value, std::string& error) {
  value = 0;
  if (address % size != 0) {
    error = "unaligned " + std::to_string(size) + "-byte read at " + hex32(address);
    return false;
  }
  if (Nvmctrl::in_nvm_space(address)) {
    value = nvm().read_memory(address, size);
    return !refused(error);
  }
  if (in(address, kRamBase, kRamSize)) {
    for (unsigned i = 0; i < size; ++i) value |= static_cast<uint32_t>(ram_[address - kRamBase + i]) << (8 * i);
    return true;
  }
  if ((address & ~3u) == kDsuDid) {
    const uint32_t mask = size == 4 ? 0xFFFFFFFFu : (1u << (8 * size)) - 1;
    value = (kDeviceId >> (8 * (address & 3u))) & mask;
    return true;
  }
  if (peripheral(address)) {
    value = chip_.bus_read(address, size);
    return !refused(error);
  }
  error = "read of " + hex32(address) + ": nothing there in the bootloader's memory map";
  return false;
}

bool BareChip::write(uint32_t address, uint32_t value, unsigned size, std::string& error) {
  if (address % size != 0) {
    error = "unaligned " + std::to_string(size) + "-byte write at " + hex32(address);
    return false;
  }
  if (Nvmctrl::in_nvm_space(address)) {
    nvm().write_memory(address, value, size);
    return !refused(error);
  }
  if (in(address, kRamBase, kRamSize)) {
    for (unsigned i = 0; i < size; ++i) ram_[address - kRamBase + i] = static_cast<uint8_t>(value >> (8 * i));
    return true;
  }
  if (peripheral(address)) {
    chip_.bus_write(address, value, size);
    return !refused(error);
  }
  error = "write of " + hex32(value) + " to " + hex32(address) + ": nothing writable there in the bootloader's memory map";
  return false;
}

}  // namespace hmc::emu
