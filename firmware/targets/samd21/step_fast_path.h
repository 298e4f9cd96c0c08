// The step engine's port on the SAMD21 (step_engine.h): the step interrupt reaches the PORT,
// the step timer's compares and flags, the STEP pulses' DMA words and SysTick directly, with no
// virtual call. main.cpp puts the interrupt (irq_tc4, which inlines all of this) in RAM.
//
//  - STEP by the DMA (step_pulses.h): arm() writes the mask of the motors stepping at `when`, the
//    pulse's end (when + kStepHighTicks), then CC0; CC0's match raises them (PORT OUTSET) and
//    moves CC1 to the end, whose match lowers every STEP pin (OUTCLR). A pulse overlapping an
//    earlier one of another motor moves that one's end later (by less than kStepHighTicks:
//    docs/firmware.md, "The step engine", for the low time this leaves), never earlier.
//  - Entry: INTFLAG holding MC0 alone (the compare the last interrupt armed, no overflow) is the
//    fast entry: its pulse is already timed, so the flag is cleared and the bookkeeping done.
//    Anything else (the main loop's pend, an overflow) first zeroes the DMA's set mask (an armed
//    compare then raises nothing) and parks CC0, then goes through
//    StepTimer::take_step_interrupt (flags cleared, overflow counted, the counter read as "now").
//  - STEP by the CPU (an event waited for inside the interrupt, or due at a slow entry): CC1 set
//    to the clock + kStepHighTicks + kRaiseSlackTicks, its synchronisation waited for (so an
//    earlier CC1 still pending cannot end the new pulse), then one IOBUS OUTSET: the pulse is at
//    least kStepHighTicks.
//  - The clock: the step timer (TC4+TC5, 32 bits, step_timer.h) counts the 48 MHz CPU clock;
//    reading it takes a read request and a synchronisation wait. SysTick counts the same clock
//    down through 24 bits (ARMv6-M ARM, "The system timer, SysTick") and reads in one load, so
//    the interrupt's "now" is the timer's calibrated offset minus SysTick (StepTimer::
//    systick_offset), extended to 32 bits around a known time. Against it an event is armed only
//    kCostTicks or more ahead, and waits end at the event's time, however late the entry.
#pragma once

#include <stdint.h>

#include "board.h"
#include "core/step_engine.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_port.h"
#include "regs_system.h"
#include "regs_timer.h"
#include "step_pulses.h"
#include "step_timer.h"

namespace hmc::samd21 {

namespace step_fast_path_detail {

inline constexpr uint32_t kIobusStep =
    port::kIobusBase + board::kDrivers[0].step.group * port::kGroupStride;

}  // namespace step_fast_path_detail

// Every member forced inline: the interrupt runs in RAM, and an out-of-line copy would land in
// flash, reached through a veneer (flash wait states; the veneers' order differs with -g).
class Samd21StepPort {
 public:
  // From the clock's read to CC0 live: the rest of the arm (two RAM stores, the CC0 store) and
  // CC0's synchronisation (5 GCLK periods, datasheet "TC", "Synchronization"), plus the clock's
  // lag behind the counter (up to 12: step_timer.h), with a margin. An event closer than this
  // is waited for inside the interrupt and raised by the CPU.
  static constexpr uint32_t kCostTicks = 48;
  static constexpr bool kArmedStepsByHardware = true;
  // The clock's read to the CPU's STEP write after it (the CC1 write, its synchronisation wait
  // of 5-6 GCLK periods + 2-3 bus cycles, the IOBUS store) plus the clock's lag (up to 12),
  // with a margin.
  static constexpr uint32_t kRaiseSlackTicks = 40;

  explicit Samd21StepPort(StepTimer& timer) : timer_(timer) {}

  // The armed compare, no overflow to count (INTFLAG's other flags are not interrupts here).
  HMC_STEP_INLINE bool event_fired(const fw::StepEngine&) {
    return (r8(kTc + tc::kIntFlag) & (tc::kIntOvf | tc::kIntMc0)) == tc::kIntMc0;
  }
  HMC_STEP_INLINE void ack_event() { r8(kTc + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntMc0); }
  // The DMA raised STEP and set its end at the compare.
  HMC_STEP_INLINE void fired(uint8_t, uint32_t) {}
  HMC_STEP_INLINE void disarm() { step_pulse_words.set_mask = 0; }
  // CC0 to a time already past once the write is live: the DMA on MC0 (the set, and the end's
  // move) stays idle until the counter wraps (89 s); by then any entry has re-armed or parked it.
  HMC_STEP_INLINE void park(uint32_t now) { r32(kTc + tc::kCc0) = now; }
  HMC_STEP_INLINE uint32_t take_entry() { return timer_.take_step_interrupt(); }

  HMC_STEP_INLINE void step_high(uint8_t motors, uint32_t near) {
    r32(kTc + tc::kCc1) = near + ticks_since(near) + fw::kStepHighTicks + kRaiseSlackTicks;
    wait_clear8(kTc + tc::kStatus, tc::kSyncBusy);
    r32(step_fast_path_detail::kIobusStep + port::kOutSet) = step_pulse_words.masks[motors];
  }
  HMC_STEP_INLINE uint32_t stopwatch() { return 0; }  // the clock is read instead (ticks_until)
  HMC_STEP_INLINE void step_low(uint8_t, uint32_t) {}  // CC1's DMA ends every pulse
  HMC_STEP_INLINE void set_dir(uint8_t index, bool reverse) {
    pin_set(board::kDrivers[index].dir, reverse);
  }
  // `entry` (the entry's event time or clock) is within the interrupt's run of now: an event far
  // from it (beyond the 24-bit clock's reach) is far from now.
  HMC_STEP_INLINE int32_t ticks_until(uint32_t when, uint32_t entry, uint32_t) {
    const int32_t ahead = static_cast<int32_t>(when - entry);
    if (HMC_STEP_UNLIKELY(ahead >= kFarTicks)) return ahead;
    return -static_cast<int32_t>(ticks_since(when));
  }
  // Only for an event less than kCostTicks away.
  HMC_STEP_INLINE void wait_until(uint32_t when, uint32_t, uint32_t) {
    while (static_cast<int32_t>(ticks_since(when)) < 0) {
    }
  }
  // The DMA's words first: the old CC0 is past, so nothing matches before the new one is live.
  // No wait for the write's synchronisation: a later write to the timer stalls until it is done.
  HMC_STEP_INLINE void arm(uint32_t when, uint8_t motors) {
    StepPulseWords& w = *fw::step_engine_detail::based(&step_pulse_words);
    w.set_mask = w.masks[motors];
    w.end = when + fw::kStepHighTicks;
    r32(kTc + tc::kCc0) = when;
  }

 private:
  static constexpr uint32_t kTc = tc::kTc4;
  static constexpr int32_t kFarTicks = int32_t{1} << 22;  // 87 ms, half the clock's reach
  // Now minus `t` (a time within 2^23 ticks of now), from the SysTick-based clock.
  HMC_STEP_INLINE uint32_t ticks_since(uint32_t t) {
    const uint32_t d = (timer_.systick_offset() - r32(systick::kCvr) - t) << 8;
    return static_cast<uint32_t>(static_cast<int32_t>(d) >> 8);
  }
  StepTimer& timer_;
};

// The step timer's interrupt: plays the rings (in RAM with its callees, main.cpp).
HMC_STEP_INLINE void run_step_fast_path(StepTimer& timer, fw::StepEngine& engine) {
  Samd21StepPort port(timer);
  fw::run_step_interrupt(engine, port);
}

}  // namespace hmc::samd21
