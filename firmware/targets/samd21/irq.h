// Interrupt control on the Cortex-M0+: global masking (PRIMASK) for short critical sections,
// and the NVIC's enable, pend and priority registers (ARMv6-M Architecture Reference Manual,
// "Nested Vectored Interrupt Controller"; the M0+ implements 2 priority bits, 7:6 of each byte).
#pragma once

#include <stdint.h>

#include "reg_access.h"
#include "regs_system.h"

namespace hmc::samd21 {

// Masks interrupts and returns the previous mask, for irq_restore().
inline uint32_t irq_save() {
  uint32_t primask;
  __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
  return primask;
}
inline void irq_restore(uint32_t primask) {
  __asm__ volatile("msr primask, %0" ::"r"(primask) : "memory");
}
inline void irq_disable_all() { __asm__ volatile("cpsid i" ::: "memory"); }
inline void irq_enable_all() { __asm__ volatile("cpsie i" ::: "memory"); }

// Masks interrupts and undoes whatever a bootloader left enabled or pending: every NVIC line
// off and cleared, SysTick stopped. Its handlers are not this firmware's.
inline void irq_quiesce() {
  irq_disable_all();
  r32(nvic::kIcer) = 0xFFFFFFFFu;
  r32(nvic::kIcpr) = 0xFFFFFFFFu;
  r32(systick::kCsr) = 0;
  r32(scb::kIcsr) = scb::kIcsrPendStClr;
}

inline void nvic_enable(uint32_t irq) { r32(nvic::kIser) = 1u << irq; }
inline void nvic_disable(uint32_t irq) { r32(nvic::kIcer) = 1u << irq; }
// Makes the interrupt pending in software: it runs as soon as its priority allows.
inline void nvic_pend(uint32_t irq) { r32(nvic::kIspr) = 1u << irq; }
inline void nvic_unpend(uint32_t irq) { r32(nvic::kIcpr) = 1u << irq; }

// Priority 0 (highest) to 3. IPR registers take word accesses only on ARMv6-M.
inline void nvic_set_priority(uint32_t irq, uint32_t priority) {
  const uint32_t address = nvic::kIpr0 + 4u * (irq / 4u);
  const uint32_t shift = 8u * (irq % 4u) + 6u;
  r32(address) = (r32(address) & ~(3u << shift)) | ((priority & 3u) << shift);
}

}  // namespace hmc::samd21
