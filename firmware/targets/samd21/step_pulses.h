// The STEP pulses, made by hardware, one compare timer per motor (step_timer.h: TC4 for motor 1,
// TCC1 for motor 2, TCC2 for motor 3). On each, compare channel 0 (the motor's step interrupt's
// compare) triggers two DMA channels: the first writes the lane's set mask to PORT OUTSET (STEP
// rises), the second the pulse's end to the same timer's CC1; compare channel 1's match triggers
// a third, which writes the motor's STEP pin to PORT OUTCLR (STEP falls). Lane i uses channels
// kStepFirstDmaChannel + 3i (set), + 1 (end), + 2 (clear).
// Each channel's descriptor links to itself, so they run for ever with no CPU. The interrupt
// arms an event by writing the mask, the end (the event's time + kStepHighTicks, in the timer's
// counts) and CC0 (step_fast_path.h): the pulse then rises at the exact tick armed (the DMAC's
// own delay aside, the same for every step) and ends kStepHighTicks later, however late the
// interrupt comes, and whatever the other motors do.
//
// The DMAC writes PORT through the APB bridge, not the IOBUS (the CPU's alone): every STEP pin
// must be in one port group (pin_map.h checks it). The channels run on arbitration level 1,
// above the LED strips' (level 0): a STEP edge has no slack, while a strip's SERCOM has a byte of
// buffer, so a strip beat waits, never a STEP edge. Within the level the lower channel goes
// first (datasheet "DMAC", static arbitration): a lane's set before its end.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

inline constexpr uint32_t kStepFirstDmaChannel = 2;
inline constexpr uint32_t kStepDmaChannelsPerLane = 3;
inline constexpr uint32_t kStepDmaLevel = 1;

// What the DMAC reads for one lane, and what its interrupt needs besides: one RAM block, so the
// interrupt reaches all of it from one address.
struct StepLaneWords {
  // The STEP pin the next CC0 match raises; 0 while nothing is armed (the counter wraps, and CC0
  // then matches again).
  volatile uint32_t set_mask;
  // CC1 from the next CC0 match on: the armed event's time + kStepHighTicks, in the timer's
  // counts.
  volatile uint32_t end;
  uint32_t pin;     // the lane's STEP pin, in the port group's OUTSET / OUTCLR
  uint32_t offset;  // the lane's timer's count minus the step clock's (step_timer.h)
  // StepTimer::systick_offset, copied here so the interrupt reaches its clock from the same
  // base register as the rest.
  uint32_t systick_offset;
};
extern StepLaneWords step_lane_words[3];

// Starts the nine channels (after dma_init, before the step timers count).
void step_pulses_start();

}  // namespace hmc::samd21
