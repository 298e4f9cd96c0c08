// The step engine's ports on the SAMD21 (step_engine.h), one per lane: each lane's interrupt
// reaches the PORT, its compare timer's registers (step_timer.h's kStepCompares), its STEP
// pulse's DMA words and SysTick directly, with no virtual call. main.cpp puts the interrupts
// (irq_tc4, irq_tcc1, irq_tcc2, which inline all of this) in RAM.
//
//  - STEP by the DMA (step_pulses.h): arm() writes the lane's set mask (its pin, or 0 for an
//    event that does not step), the pulse's end (when + kStepHighTicks) and CC0, both in the
//    lane's timer's counts; CC0's match raises the pin (PORT OUTSET) and moves the lane's CC1 to
//    the end, whose match lowers it (OUTCLR).
//  - Entry: the lane's MC0 flag with its compare armed and nothing asked is the fast entry: its
//    pulse is already timed, so the flag is cleared and the bookkeeping done. A request from the
//    main loop first zeroes the set mask (an armed compare then raises nothing) and parks CC0,
//    then reads the clock (motor 1's through StepTimer::take_step_interrupt: flags cleared,
//    overflow counted). Motor 1's entry counts an overflow whatever brought it.
//  - STEP by the CPU (an event waited for inside the interrupt, or due at a slow entry): the
//    lane's CC1 set to the clock + kStepHighTicks + kRaiseSlackTicks, its synchronisation waited
//    for (so an earlier CC1 still pending cannot end the new pulse), then one IOBUS OUTSET: the
//    pulse is at least kStepHighTicks.
//  - The clock: the step timer (TC4+TC5, 32 bits, step_timer.h) counts the 48 MHz CPU clock;
//    reading it takes a read request and a synchronisation wait. SysTick counts the same clock
//    down through 24 bits (ARMv6-M ARM, "The system timer, SysTick") and reads in one load, so
//    the interrupt's "now" is the timer's calibrated offset minus SysTick (StepTimer::
//    systick_offset), extended to 32 bits around a known time. Against it an event is armed only
//    kCostTicks or more ahead, and waits end at the event's time, however late the entry.
//  - Reach: a compare written up to half its counter's values ahead matches at its time; a
//    later event is reached through relays (step_engine.h): 2^15 ticks (683 µs) on TCC2.
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

// Lane `Lane`'s port (kStepCompares[Lane]). Every member forced inline: the interrupts run in
// RAM, and an out-of-line copy would land in flash, reached through a veneer (flash wait states;
// the veneers' order differs with -g).
template <uint8_t Lane>
class Samd21StepPort {
 public:
  static constexpr uint8_t kLane = Lane;
  // From the clock's read to CC0 live: the rest of the arm (two RAM stores, the CC0 store) and
  // CC0's synchronisation (5 GCLK periods, datasheet "TC" and "TCC", "Synchronization"), plus
  // the clock's lag behind the counter (up to 12: step_timer.h), with a margin. An event closer
  // than this is waited for inside the interrupt and raised by the CPU.
  static constexpr uint32_t kCostTicks = 48;
  // Half the counter's values: a compare written this far ahead or less matches at its time.
  static constexpr uint32_t kReachTicks = kStepCompares[Lane].count_mask / 2 + 1;
  static constexpr bool kArmedStepsByHardware = true;
  // The clock's read to the CPU's STEP write after it (the CC1 write, its synchronisation wait
  // of 5-6 GCLK periods + 2-3 bus cycles, the IOBUS store) plus the clock's lag (up to 12),
  // with a margin.
  static constexpr uint32_t kRaiseSlackTicks = 40;

  explicit Samd21StepPort(StepTimer& timer) : timer_(timer) {}

  // The lane's compare has matched. Motor 1's timer also counts the clock's overflows here.
  HMC_STEP_INLINE bool event_fired(const fw::StepEngine&) {
    if constexpr (kC.is_tc) {
      const uint8_t flags = r8(kC.base + tc::kIntFlag);
      if (HMC_STEP_UNLIKELY((flags & tc::kIntOvf) != 0)) timer_.count_overflow();
      return (flags & tc::kIntMc0) != 0;
    } else {
      // MC0 (bit 16) shifted into the sign: one shift, no mask to load.
      static_assert(tcc::kIntMc0 == 1u << 16, "");
      return static_cast<int32_t>(r32(kC.base + tcc::kIntFlag) << 15) < 0;
    }
  }
  HMC_STEP_INLINE void ack_event() {
    if constexpr (kC.is_tc) {
      r8(kC.base + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntMc0);
    } else {
      r32(kC.base + tcc::kIntFlag) = tcc::kIntMc0;
    }
  }
  // The DMA raised STEP and set its end at the compare.
  HMC_STEP_INLINE void fired(uint32_t) {}
  // A TCC's parked compare comes round with its counter (every 2^16 ticks on TCC2): its
  // interrupt is off while nothing is armed, and on again with the next arm (whose entry clears
  // any flag the parked compare left).
  HMC_STEP_INLINE void disarm() {
    step_lane_words[Lane].set_mask = 0;
    if constexpr (!kC.is_tc) r32(kC.base + tcc::kIntEnClr) = tcc::kIntMc0;
  }
  // CC0 to a time already past once the write is live: the DMA on MC0 (the set, and the end's
  // move) stays idle until the counter wraps; by then the lane has re-armed or parked it, or
  // the match finds the set mask 0 and the interrupt only clears its flag.
  HMC_STEP_INLINE void park(uint32_t now) { r32(kC.base + kC.cc0) = counts(now); }
  HMC_STEP_INLINE uint32_t take_entry() {
    if constexpr (kC.is_tc) {
      return timer_.take_step_interrupt();
    } else {
      r32(kC.base + tcc::kIntFlag) = tcc::kIntMc0;
      return timer_.read_low();
    }
  }

  HMC_STEP_INLINE void step_high(uint32_t near) {
    r32(kC.base + kC.cc1) =
        counts(near + ticks_since(near) + fw::kStepHighTicks + kRaiseSlackTicks);
    if constexpr (kC.is_tc) {
      wait_clear8(kC.base + tc::kStatus, tc::kSyncBusy);
    } else {
      while ((r32(kC.base + tcc::kSyncBusy) & tcc::sync_cc(1)) != 0) {
      }
    }
    r32(step_fast_path_detail::kIobusStep + port::kOutSet) = step_lane_words[Lane].pin;
  }
  HMC_STEP_INLINE uint32_t stopwatch() { return 0; }  // the clock is read instead (ticks_until)
  HMC_STEP_INLINE void step_low(uint32_t) {}  // CC1's DMA ends every pulse
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
  HMC_STEP_INLINE void arm(uint32_t when, bool step) {
    StepLaneWords& w = *fw::step_engine_detail::based(&step_lane_words[Lane]);
    w.set_mask = step ? w.pin : 0;
    rearm(when);
    if constexpr (!kC.is_tc) r32(kC.base + tcc::kIntEnSet) = tcc::kIntMc0;
  }
  HMC_STEP_INLINE void rearm(uint32_t when) {
    StepLaneWords& w = *fw::step_engine_detail::based(&step_lane_words[Lane]);
    const uint32_t at = when + offset(w);
    w.end = (at + fw::kStepHighTicks) & kC.count_mask;
    r32(kC.base + kC.cc0) = at & kC.count_mask;
  }

 private:
  static constexpr StepCompare kC = kStepCompares[Lane];
  static constexpr int32_t kFarTicks = int32_t{1} << 22;  // 87 ms, half the clock's reach
  // Motor 1's timer is the clock: no offset to load.
  HMC_STEP_INLINE static uint32_t offset(const StepLaneWords& w) {
    if constexpr (Lane == 0) {
      return 0;
    } else {
      return w.offset;
    }
  }
  // A clock time in the lane's timer's counts.
  HMC_STEP_INLINE static uint32_t counts(uint32_t t) {
    return (t + offset(step_lane_words[Lane])) & kC.count_mask;
  }
  // Now minus `t` (a time within 2^23 ticks of now), from the SysTick-based clock.
  HMC_STEP_INLINE uint32_t ticks_since(uint32_t t) {
    const uint32_t d = (step_lane_words[Lane].systick_offset - r32(systick::kCvr) - t) << 8;
    return static_cast<uint32_t>(static_cast<int32_t>(d) >> 8);
  }
  StepTimer& timer_;
};

// Lane `Lane`'s step interrupt, in two parts (main.cpp puts each in RAM): the express entry,
// true when it took the event, and the full one otherwise (out of line: its registers and stack
// frame are not the express entry's).
template <uint8_t Lane>
HMC_STEP_INLINE bool run_step_express(StepTimer& timer, fw::StepEngine& engine) {
  Samd21StepPort<Lane> port(timer);
  return fw::run_lane_express(engine, port);
}
template <uint8_t Lane>
HMC_STEP_INLINE void run_step_general(StepTimer& timer, fw::StepEngine& engine) {
  Samd21StepPort<Lane> port(timer);
  fw::run_lane_general(engine, port);
}

}  // namespace hmc::samd21
