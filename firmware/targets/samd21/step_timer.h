// StepTimer on the SAMD21: the step clock and the three motors' compares (kStepCompares).
//  - The clock: TC4 and TC5 chained as one 32-bit counter at 48 MHz (the CPU clock), extended to
//    64 bits in software by counting overflows, and SysTick free-running at the CPU clock for
//    the step interrupts' short waits (step_fast_path.h).
//  - One compare timer per motor, so no motor's event waits for another's: motor 1 on TC4
//    itself, motor 2 on TCC1 (24 bits), motor 3 on TCC2 (16 bits), all counting the same 48 MHz
//    clock, free-running (TCC: normal PWM with PER at its top, its outputs on no pin). On each,
//    compare channel 0 is the motor's step interrupt (IRQ 19, 16, 17, all at the highest
//    priority) and its STEP's rise, compare channel 1 its end (both by DMA: step_pulses.h;
//    start() needs dma_init() done). A lane's times are the clock's plus its offset
//    (StepLaneWords::offset, measured by start() against SysTick), modulo its counter's width.
//    TCC0 stays the servos' and TC3 the buzzer's; TCC2 shares TC3's generic clock channel, both
//    on the CPU clock.
//
// Contract: now() is the 64-bit tick count (main loop). The step interrupts work on the low 32
// bits (step_engine.h) and own the compares: their ports (step_fast_path.h) write CC0 and clear
// the compare's flags themselves; an entry by anything else calls take_step_interrupt() (motor
// 1's, which also counts an overflow) or read_low(). schedule(when), the core's "run the
// interrupts now" (StepScheduler::kick), pends all three.
//
// Counter reads use a read request per read (READREQ.RREQ), not continuous read
// synchronisation: the value is then the count at the request, never an older one, which the
// "already past" check needs.
#pragma once

#include <stdint.h>

#include "board.h"  // before the register namespaces: its pin map's tc() and tcc() are functions
#include "core/hal.h"
#include "reg_access.h"
#include "regs_dmac.h"
#include "regs_system.h"
#include "regs_timer.h"

namespace hmc::samd21 {

// One motor's compare timer: its registers, its counter's width and its interrupt and DMA
// triggers.
struct StepCompare {
  uint32_t base;
  bool is_tc;  // TC4's register layout, else a TCC's
  uint32_t cc0;
  uint32_t cc1;
  uint32_t count_mask;
  uint32_t irq;
  uint32_t trigger_mc0;
  uint32_t trigger_mc1;
};
inline constexpr StepCompare kStepCompares[3] = {
    {tc::kTc4, true, tc::kCc0, tc::kCc1, 0xFFFFFFFFu, irqn::kTc4, dmac::kTriggerTc4Mc0,
     dmac::kTriggerTc4Mc1},
    {tcc::kTcc1, false, tcc::cc(0), tcc::cc(1), 0xFFFFFFu, irqn::kTcc1, dmac::kTriggerTcc1Mc0,
     dmac::kTriggerTcc1Mc1},
    {tcc::kTcc2, false, tcc::cc(0), tcc::cc(1), 0xFFFFu, irqn::kTcc2, dmac::kTriggerTcc2Mc0,
     dmac::kTriggerTcc2Mc1},
};

class StepTimer final : public hal::StepTimer {
 public:
  // Clocks, resets and starts the counter; enables its interrupt at board priority.
  void start();

  hal::Ticks now() const override;
  void schedule(hal::Ticks when) override;

  // The step interrupts' calls, inline: they run in RAM, and a call to flash would go through a
  // veneer (flash wait states; the veneers' order differs with -g).
  // The counter's low 32 bits (a read request and its synchronisation).
  uint32_t read_low() const {
    r16(tc::kTc4 + tc::kReadReq) = tc::kReadCount;
    wait_clear8(tc::kTc4 + tc::kStatus, tc::kSyncBusy);
    return r32(tc::kTc4 + tc::kCount);
  }
  // Counts an overflow whose flag is set, and clears it (motor 1's interrupt).
  void count_overflow() {
    r8(tc::kTc4 + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntOvf);
    high_ = high_ + 1u;
  }
  // Motor 1's interrupt entered by a pend or an overflow: clears both flags, counts an overflow,
  // and returns the counter (low 32 bits).
  uint32_t take_step_interrupt() {
    if ((r8(tc::kTc4 + tc::kIntFlag) & tc::kIntOvf) != 0) count_overflow();
    r8(tc::kTc4 + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntMc0);  // write 1 to clear
    return read_low();
  }
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
