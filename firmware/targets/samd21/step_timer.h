// StepTimer on the SAMD21: TC4 and TC5 chained as one 32-bit counter at 48 MHz (the CPU clock),
// extended to 64 bits in software by counting overflows, with compare channel 0 as the step
// interrupt (TC4's IRQ 19, the highest priority) and the STEP pulses' rise, compare channel 1 as
// their end (both by DMA: step_pulses.h; start() needs dma_init() done), and SysTick
// free-running at the CPU clock for the step interrupt's short waits (step_fast_path.h).
//
// Contract: now() is the 64-bit tick count (main loop). The step interrupt works on the low 32
// bits (step_engine.h) and owns the compare: its port (step_fast_path.h) writes CC0 and clears
// the compare's flag itself; an entry by anything else calls take_step_interrupt(), which
// clears the flags, counts an overflow and returns the counter as the interrupt's "now".
// schedule(when), the core's "run the interrupt now" (StepScheduler::kick), pends the
// interrupt.
//
// Counter reads use a read request per read (READREQ.RREQ), not continuous read
// synchronisation: the value is then the count at the request, never an older one, which the
// "already past" check needs.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class StepTimer final : public hal::StepTimer {
 public:
  // Clocks, resets and starts the counter; enables its interrupt at board priority.
  void start();

  hal::Ticks now() const override;
  void schedule(hal::Ticks when) override;

  // The interrupt entered by a pend or an overflow: clears both flags, counts an overflow, and
  // returns the counter (low 32 bits).
  uint32_t take_step_interrupt();
  // SysTick counts the same 48 MHz clock down through 24 bits: this minus SysTick is the
  // counter's low 24 bits, read with one load and no synchronisation wait (set by start(); up
  // to 12 ticks behind the counter, never ahead).
  uint32_t systick_offset() const { return systick_offset_; }

 private:
  hal::Ticks now_masked() const;  // with interrupts masked

  volatile uint32_t high_ = 0;  // overflows counted so far
  uint32_t systick_offset_ = 0;
};

}  // namespace hmc::samd21
