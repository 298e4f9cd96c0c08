// Memory-mapped register access for the SAMD21 port: one place that turns an address into a
// volatile reference, and small helpers that keep -Wconversion quiet on 8/16-bit registers.
// The addresses themselves live in the regs_*.h headers, one per group of peripherals.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

inline volatile uint8_t& r8(uint32_t address) {
  return *reinterpret_cast<volatile uint8_t*>(address);
}
inline volatile uint16_t& r16(uint32_t address) {
  return *reinterpret_cast<volatile uint16_t*>(address);
}
inline volatile uint32_t& r32(uint32_t address) {
  return *reinterpret_cast<volatile uint32_t*>(address);
}

// Read-modify-write helpers (not atomic: callers own the register or mask interrupts).
inline void set8(uint32_t address, uint32_t bits) {
  r8(address) = static_cast<uint8_t>(r8(address) | bits);
}
inline void clear8(uint32_t address, uint32_t bits) {
  r8(address) = static_cast<uint8_t>(r8(address) & ~bits);
}
inline void set16(uint32_t address, uint32_t bits) {
  r16(address) = static_cast<uint16_t>(r16(address) | bits);
}
inline void set32(uint32_t address, uint32_t bits) { r32(address) = r32(address) | bits; }
inline void clear32(uint32_t address, uint32_t bits) { r32(address) = r32(address) & ~bits; }

// Spins while any of `bits` is set in an 8/16/32-bit status register (synchronisation).
inline void wait_clear8(uint32_t address, uint32_t bits) {
  while ((r8(address) & bits) != 0) {
  }
}
inline void wait_clear32(uint32_t address, uint32_t bits) {
  while ((r32(address) & bits) != 0) {
  }
}

}  // namespace hmc::samd21
