// The step engine's port on the SAMD21 (step_engine.h): the step interrupt reaches the PORT,
// the step timer's compare and flags and SysTick directly, with no virtual call. main.cpp puts
// the interrupt (irq_tc4, which inlines all of this) in RAM.
//
//  - Entry: INTFLAG holding MC0 alone (the compare the last interrupt armed, no overflow) is the
//    fast entry: STEP rises at once from the masks that interrupt prepared. Anything else (the
//    main loop's pend, an overflow) goes through StepTimer::take_step_interrupt (flags cleared,
//    overflow counted, the counter read as "now").
//  - STEP: every driver's STEP pin is a plain GPIO output (board::kDrivers); the motors due at
//    one time are raised with one OUTSET write per port group through the single-cycle IOBUS
//    and lowered with one OUTCLR write. Nothing depends on which timer outputs a pin has, so any
//    GPIO pin may carry STEP (docs/firmware.md, "What the wiring must allow").
//  - Pulse width: SysTick counts the 48 MHz CPU clock down through 24 bits (ARMv6-M ARM, "The
//    system timer, SysTick"); a read is one load with no clock-domain synchronisation (the TC
//    counter needs a read request and a synchronisation wait). The pulse ends once SysTick has
//    moved kStepHighTicks since the read right after the rising edge's write: the difference
//    of two reads is the cycles between them exactly, so the spin can only lengthen the pulse.
//  - Time: the step timer (TC4+TC5, 32 bits, step_timer.h) at the same 48 MHz. The compare is
//    written without waiting for its synchronisation, while the pulse is high, and only for an
//    event at least kCostTicks away; closer events are waited for on SysTick.
#pragma once

#include <stdint.h>

#include "board.h"
#include "core/step_engine.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_port.h"
#include "regs_system.h"
#include "regs_timer.h"
#include "step_timer.h"

namespace hmc::samd21 {

namespace step_fast_path_detail {

// OUTSET/OUTCLR masks of port group `group` for each set of motors (bit m−1 for motor m).
struct StepMasks {
  uint32_t of[8];
};
constexpr StepMasks step_masks(uint8_t group) {
  StepMasks masks{};
  for (uint8_t motors = 0; motors < 8; ++motors) {
    for (uint8_t i = 0; i < 3; ++i) {
      const board::Pin pin = board::kDrivers[i].step;
      if ((motors & (1u << i)) != 0 && pin.group == group) masks.of[motors] |= 1u << pin.number;
    }
  }
  return masks;
}
inline constexpr StepMasks kGroupA = step_masks(0);
inline constexpr StepMasks kGroupB = step_masks(1);
inline constexpr bool kAnyOnB = kGroupB.of[7] != 0;
inline constexpr uint32_t kIobusA = port::kIobusBase;
inline constexpr uint32_t kIobusB = port::kIobusBase + port::kGroupStride;

}  // namespace step_fast_path_detail

class Samd21StepPort {
 public:
  // From a compare value written to the interrupt at that time on a fast-path entry: the
  // rest of the pass, the compare's synchronisation (5 GCLK periods, datasheet "TC",
  // "Synchronization"), the exit and the next entry, with a margin: an event closer than this
  // is waited for inside the interrupt.
  static constexpr uint32_t kCostTicks = 192;

  explicit Samd21StepPort(StepTimer& timer) : timer_(timer) {}

  // The armed compare, no overflow to count (INTFLAG's other flags are not interrupts here).
  bool event_fired(const fw::StepEngine&) {
    return (r8(kTc + tc::kIntFlag) & (tc::kIntOvf | tc::kIntMc0)) == tc::kIntMc0;
  }
  void ack_event() { r8(kTc + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntMc0); }
  uint32_t take_entry() { return timer_.take_step_interrupt(); }

  void step_high(uint8_t motors) {
    using namespace step_fast_path_detail;
    r32(kIobusA + port::kOutSet) = kGroupA.of[motors];
    if (kAnyOnB) r32(kIobusB + port::kOutSet) = kGroupB.of[motors];
  }
  // SysTick counts down through 24 bits: marks are its raw values, differences masked.
  uint32_t stopwatch() { return r32(systick::kCvr); }
  uint32_t elapsed(uint32_t mark) { return (mark - r32(systick::kCvr)) & 0xFFFFFFu; }
  void step_low(uint8_t motors, uint32_t mark) {
    using namespace step_fast_path_detail;
    while (elapsed(mark) < fw::kStepHighTicks) {
    }
    r32(kIobusA + port::kOutClr) = kGroupA.of[motors];
    if (kAnyOnB) r32(kIobusB + port::kOutClr) = kGroupB.of[motors];
  }
  void set_dir(uint8_t index, bool reverse) { pin_set(board::kDrivers[index].dir, reverse); }
  void wait_for(uint32_t mark, uint32_t ticks) {
    while (elapsed(mark) < ticks) {
    }
  }
  // No wait for the write's synchronisation: the pulse's wait covers it, and a later write to
  // the timer stalls until it is done.
  void arm(uint32_t when) { r32(kTc + tc::kCc0) = when; }

 private:
  static constexpr uint32_t kTc = tc::kTc4;
  StepTimer& timer_;
};

// The step timer's interrupt: plays the rings (in RAM with its callees, main.cpp).
HMC_STEP_INLINE void run_step_fast_path(StepTimer& timer, fw::StepEngine& engine) {
  Samd21StepPort port(timer);
  fw::run_step_interrupt(engine, port);
}

}  // namespace hmc::samd21
