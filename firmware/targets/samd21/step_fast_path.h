// The step engine's port on the SAMD21 (step_engine.h): the step interrupt reaches the PORT,
// the step timer's compare and SysTick directly, with no virtual call.
//
//  - STEP: every driver's STEP pin is a plain GPIO output (board::kDrivers); the motors due at
//    one time are raised with one OUTSET write per port group through the single-cycle IOBUS
//    and lowered with one OUTCLR write. Nothing depends on which timer outputs a pin has, so any
//    GPIO pin may carry STEP (docs/firmware.md, "Step pins").
//  - Pulse width: SysTick counts the 48 MHz CPU clock down through 24 bits (ARMv6-M ARM, "The
//    system timer, SysTick"); a read is one load with no clock-domain synchronisation (the TC
//    counter needs a read request and a synchronisation wait). The pulse ends once SysTick has
//    moved kStepHighTicks since the read right after the rising edge's write.
//  - Time: the step timer (TC4+TC5, 32 bits, step_timer.h) at the same 48 MHz. The interrupt's
//    "now" is the compare value that fired (StepTimer::take_step_interrupt), what it spent since
//    comes from SysTick, and the next compare is written only when it is at least kCostTicks
//    away; closer events are waited for on SysTick inside the interrupt.
#pragma once

#include <stdint.h>

#include "board.h"
#include "core/step_engine.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_port.h"
#include "regs_system.h"
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
  // The interrupt's exit, the next entry and the work before the compare is live (an estimate
  // to be replaced by the emulator's measured cycles); a closer event is waited for.
  static constexpr uint32_t kCostTicks = 192;

  Samd21StepPort(StepTimer& timer, uint32_t entry) : timer_(timer), entry_(entry) {}

  void step_high(uint8_t motors) {
    using namespace step_fast_path_detail;
    r32(kIobusA + port::kOutSet) = kGroupA.of[motors];
    if (kAnyOnB) r32(kIobusB + port::kOutSet) = kGroupB.of[motors];
  }
  uint32_t pulse_started() { return r32(systick::kCvr); }
  void step_low(uint8_t motors, uint32_t since) {
    using namespace step_fast_path_detail;
    while (((since - r32(systick::kCvr)) & 0xFFFFFFu) < fw::kStepHighTicks) {
    }
    r32(kIobusA + port::kOutClr) = kGroupA.of[motors];
    if (kAnyOnB) r32(kIobusB + port::kOutClr) = kGroupB.of[motors];
  }
  void set_dir(uint8_t index, bool reverse) { pin_set(board::kDrivers[index].dir, reverse); }
  uint32_t elapsed() { return (entry_ - r32(systick::kCvr)) & 0xFFFFFFu; }
  void wait_for(uint32_t ticks) {
    while (elapsed() < ticks) {
    }
  }
  void arm(uint32_t when) { timer_.arm(when); }

 private:
  StepTimer& timer_;
  uint32_t entry_;  // SysTick at the interrupt's entry
};

// The step timer's interrupt: counts an overflow, takes the entry time and plays the rings.
inline void run_step_fast_path(StepTimer& timer, fw::StepEngine& engine) {
  const uint32_t entry = r32(systick::kCvr);
  const uint32_t now = timer.take_step_interrupt();
  Samd21StepPort port(timer, entry);
  fw::run_step_interrupt(engine, port, now);
}

}  // namespace hmc::samd21
