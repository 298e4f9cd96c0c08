// StepTimer on the SAMD21: TC4 and TC5 chained as one 32-bit counter at 48 MHz (the CPU clock),
// extended to 64 bits in software by counting overflows, with compare channel 0 as the step
// interrupt (TC4's IRQ 19, the highest priority), and SysTick free-running at the CPU clock for
// the step interrupt's short waits (step_fast_path.h).
//
// Contract: now() is the 64-bit tick count (main loop). The step interrupt works on the low 32
// bits (step_engine.h): take_step_interrupt() gives its "now", arm() sets the next compare, which
// the engine writes only for a time at least its own cost away. schedule(when), the core's
// "run the interrupt now" (StepScheduler::kick), pends the interrupt for a time already past
// and arms the compare otherwise.
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

  // The interrupt's first call: clears the flags, counts an overflow, and returns the time the
  // step engine takes as now: the compare value when it fired, else (pended, or an overflow
  // alone) the counter.
  uint32_t take_step_interrupt();
  // The step interrupt: the next compare at `when` (low 32 bits).
  void arm(uint32_t when);

 private:
  hal::Ticks now_masked() const;  // with interrupts masked

  volatile uint32_t high_ = 0;   // overflows counted so far
  volatile uint32_t armed_ = 0;  // the compare value
};

}  // namespace hmc::samd21
