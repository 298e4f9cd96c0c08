// Bare-metal start for qemu's microbit machine: vector table, .data/.bss set-up, constructors,
// and the two semihosting calls the benchmark needs (BKPT 0xAB: SYS_WRITE0, SYS_EXIT).
#include <stdint.h>
#include <stddef.h>

#include "semihost.h"

extern "C" {
extern uint32_t __data_load, __data_start, __data_end, __bss_start, __bss_end, __stack_top;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
[[noreturn]] void reset_handler();
[[noreturn]] void fault_handler();
}

namespace {
uint32_t semihost(uint32_t op, const void* arg) {
  register uint32_t r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}
}  // namespace

void semihost_write(const char* text) { semihost(0x04, text); }  // SYS_WRITE0

[[noreturn]] void semihost_exit(bool ok) {
  // SYS_EXIT with ADP_Stopped_ApplicationExit (qemu exits 0) or ADP_Stopped_RunTimeErrorUnknown.
  semihost(0x18, reinterpret_cast<const void*>(ok ? 0x20026u : 0x20023u));
  for (;;) {
  }
}

extern "C" [[noreturn]] void reset_handler() {
  uint32_t* src = &__data_load;
  for (uint32_t* dst = &__data_start; dst < &__data_end;) *dst++ = *src++;
  for (uint32_t* dst = &__bss_start; dst < &__bss_end;) *dst++ = 0;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  semihost_exit(main() == 0);
}

extern "C" [[noreturn]] void fault_handler() {
  semihost_write("bench: hard fault\n");
  semihost_exit(false);
}

// Cortex-M0 vector table: initial stack pointer, reset, NMI, HardFault (the rest never fires:
// no interrupt is enabled; the benchmark calls the step interrupt's handler from main).
__attribute__((section(".vectors"), used)) const void* const vectors[4] = {
    &__stack_top, reinterpret_cast<const void*>(&reset_handler),
    reinterpret_cast<const void*>(&fault_handler), reinterpret_cast<const void*>(&fault_handler)};

// The C++ runtime bits a freestanding program with virtual destructors still references.
extern "C" void __cxa_pure_virtual() { fault_handler(); }
void operator delete(void*) noexcept {}
void operator delete(void*, size_t) noexcept {}
