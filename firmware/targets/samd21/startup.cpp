// Start-up for the SAMD21 (Cortex-M0+): the vector table and the reset handler. Reset masks
// interrupts, points VTOR at this table (a bootloader may not), copies .data from flash, zeroes
// .bss, runs the static constructors and calls main(); main() unmasks interrupts once every
// peripheral is set up. Every fault, and every interrupt without a handler of its own, lands in
// unexpected_interrupt(), which records where it happened (reset_cause.h) and resets the chip.
//
// Why mask first: after a reset PRIMASK is clear, and behind a bootloader the application is
// entered by a jump, with whatever the bootloader left running (its USB or SysTick interrupts
// enabled in the NVIC, VTOR at its own table). An interrupt taken before VTOR, .data, .bss and
// the constructors are done would run the bootloader's handler or one of ours on uninitialised
// objects. HardFault is not masked by PRIMASK, so VTOR is set right after, before anything
// that could fault.
//
// Vector layout: ARMv6-M exceptions 1-15, then the SAMD21's 28 peripheral interrupts (SAMD21
// datasheet, "Nested Vector Interrupt Controller", interrupt line mapping; HARDWARE.md lists the
// lines this port uses). Handlers are weak: main.cpp defines the ones the firmware needs.
#include <stdint.h>

#include "reg_access.h"
#include "regs_system.h"
#include "reset_cause.h"

extern "C" {

// Linker script symbols (samd21_sections.ld).
extern uint32_t __data_load__;
extern uint32_t __data_start__;
extern uint32_t __data_end__;
extern uint32_t __bss_start__;
extern uint32_t __bss_end__;
extern uint32_t __stack_top__;
extern void (*__preinit_array_start[])();
extern void (*__preinit_array_end[])();
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();

int main();
void reset_handler();
[[noreturn]] void start_application();

// The stack the exception entry used holds the faulting context's frame: EXC_RETURN bit 2 in
// LR says which (0 the main stack, 1 the process stack; this firmware uses only the main one).
__attribute__((naked)) void unexpected_interrupt() noexcept {
  __asm__ volatile(
      "movs r0, #4\n\t"
      "mov r1, lr\n\t"
      "tst r0, r1\n\t"
      "bne 1f\n\t"
      "mrs r0, msp\n\t"
      "b 2f\n"
      "1:\n\t"
      "mrs r0, psp\n"
      "2:\n\t"
      "bl record_fault_and_reset\n\t");
}

#define HMC_WEAK_HANDLER(name) void name() noexcept __attribute__((weak, alias("unexpected_interrupt")))
HMC_WEAK_HANDLER(irq_nmi);
HMC_WEAK_HANDLER(irq_hard_fault);
HMC_WEAK_HANDLER(irq_svcall);
HMC_WEAK_HANDLER(irq_pendsv);
HMC_WEAK_HANDLER(irq_systick);
HMC_WEAK_HANDLER(irq_pm);
HMC_WEAK_HANDLER(irq_sysctrl);
HMC_WEAK_HANDLER(irq_wdt);
HMC_WEAK_HANDLER(irq_rtc);
HMC_WEAK_HANDLER(irq_eic);
HMC_WEAK_HANDLER(irq_nvmctrl);
HMC_WEAK_HANDLER(irq_dmac);
HMC_WEAK_HANDLER(irq_usb);
HMC_WEAK_HANDLER(irq_evsys);
HMC_WEAK_HANDLER(irq_sercom0);
HMC_WEAK_HANDLER(irq_sercom1);
HMC_WEAK_HANDLER(irq_sercom2);
HMC_WEAK_HANDLER(irq_sercom3);
HMC_WEAK_HANDLER(irq_sercom4);
HMC_WEAK_HANDLER(irq_sercom5);
HMC_WEAK_HANDLER(irq_tcc0);
HMC_WEAK_HANDLER(irq_tcc1);
HMC_WEAK_HANDLER(irq_tcc2);
HMC_WEAK_HANDLER(irq_tc3);
HMC_WEAK_HANDLER(irq_tc4);
HMC_WEAK_HANDLER(irq_tc5);
HMC_WEAK_HANDLER(irq_tc6);
HMC_WEAK_HANDLER(irq_tc7);
HMC_WEAK_HANDLER(irq_adc);
HMC_WEAK_HANDLER(irq_ac);
HMC_WEAK_HANDLER(irq_dac);
HMC_WEAK_HANDLER(irq_ptc);
HMC_WEAK_HANDLER(irq_i2s);
#undef HMC_WEAK_HANDLER

}  // extern "C"

namespace {

using Handler = void (*)();

// Entry 0 is the initial stack pointer; the linker places this table at the image's start.
__attribute__((section(".vectors"), used)) const Handler vector_table[16 + 28] = {
    reinterpret_cast<Handler>(&__stack_top__),
    reset_handler,
    irq_nmi,
    irq_hard_fault,
    nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr,  // reserved
    irq_svcall,
    nullptr, nullptr,  // reserved
    irq_pendsv,
    irq_systick,
    // Peripheral interrupts 0-27.
    irq_pm, irq_sysctrl, irq_wdt, irq_rtc, irq_eic, irq_nvmctrl, irq_dmac, irq_usb, irq_evsys,
    irq_sercom0, irq_sercom1, irq_sercom2, irq_sercom3, irq_sercom4, irq_sercom5,
    irq_tcc0, irq_tcc1, irq_tcc2, irq_tc3, irq_tc4, irq_tc5, irq_tc6, irq_tc7,
    irq_adc, irq_ac, irq_dac, irq_ptc, irq_i2s,
};

}  // namespace

// The first instruction masks interrupts, before even the C++ function's prologue below.
extern "C" __attribute__((naked)) void reset_handler() {
  __asm__ volatile(
      "cpsid i\n\t"
      "bl start_application\n\t");
}

extern "C" void start_application() {
  hmc::samd21::r32(hmc::samd21::scb::kVtor) = reinterpret_cast<uint32_t>(&vector_table[0]);
  __asm__ volatile("dsb\n\tisb" ::: "memory");  // the table is in use from the next instruction
  uint32_t* source = &__data_load__;
  for (uint32_t* d = &__data_start__; d < &__data_end__; ++d) *d = *source++;
  for (uint32_t* d = &__bss_start__; d < &__bss_end__; ++d) *d = 0;
  for (void (**f)() = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  main();
  hmc::samd21::r32(hmc::samd21::scb::kAircr) = hmc::samd21::scb::kAircrSysReset;  // main() never returns
  for (;;) {
  }
}
