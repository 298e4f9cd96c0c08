// StepTimer on the SAMD21: TC4 and TC5 chained as one 32-bit counter at 48 MHz (the CPU clock),
// extended to 64 bits in software by counting overflows, with compare channel 0 as the step
// interrupt (TC4's IRQ 19, the highest priority).
//
// Contract (step_scheduler.h): now() is the 64-bit tick count; schedule(when) makes the interrupt
// call on_step_timer() at `when`, or at once when `when` is already past. The compare matches on
// the low 32 bits only; the interrupt compares the full 64-bit time and ignores a match whose
// high word differs (a target more than 89 s away, which the scheduler never asks for, matches
// harmlessly every 2^32 ticks until it is due). A compare written too late to match (the
// counter passed it while the write synchronised) is caught by reading the counter after the
// write and pending the interrupt in software.
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

  // The interrupt's first call: clears the flags, counts an overflow, and returns true when the
  // scheduled time has come (the caller then runs on_step_timer()).
  bool take_interrupt();

 private:
  hal::Ticks now_masked() const;  // with interrupts masked

  static constexpr hal::Ticks kNone = ~hal::Ticks{0};
  volatile uint32_t high_ = 0;        // overflows counted so far
  volatile hal::Ticks target_ = kNone;
};

}  // namespace hmc::samd21
