// The STEP pulses, made by hardware. The step timer's compare channel 0 (TC4 MC0, the step
// interrupt's compare) triggers two DMA channels: channel 2 writes the set mask
// (`step_pulse_words`) to PORT OUTSET (STEP rises) and channel 4 the pulse's end to TC4 CC1;
// compare channel 1's match (TC4 MC1) triggers channel 3, which writes every STEP pin to PORT
// OUTCLR (STEP falls).
// Each channel's descriptor links to itself, so they run for ever with no CPU. The interrupt
// arms an event by writing the mask, the end (the event's time + kStepHighTicks) and CC0
// (step_fast_path.h): the pulse then rises at the exact tick armed (the DMAC's own delay aside,
// the same for every step) and ends kStepHighTicks later, however late the interrupt comes.
//
// The DMAC writes PORT through the APB bridge, not the IOBUS (the CPU's alone): one OUTSET and
// one OUTCLR register, so every STEP pin must be in one port group (pin_map.h checks it). The
// channels run on arbitration level 1, above the LED strips' (level 0): a STEP edge has no
// slack, while a strip's SERCOM has a byte of buffer, so a strip beat waits, never a STEP edge.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

inline constexpr uint32_t kStepSetDmaChannel = 2;
inline constexpr uint32_t kStepClearDmaChannel = 3;
inline constexpr uint32_t kStepEndDmaChannel = 4;
inline constexpr uint32_t kStepDmaLevel = 1;

// What the DMAC reads at a CC0 match, and the masks the interrupt takes them from: one RAM block,
// so the interrupt reaches all of it from one address.
struct StepPulseWords {
  // The STEP pins the next CC0 match raises; 0 while nothing is armed (the 32-bit counter wraps
  // every 89 s, and CC0 then matches again).
  volatile uint32_t set_mask;
  // CC1 from the next CC0 match on: the armed event's time + kStepHighTicks.
  volatile uint32_t end;
  // The STEP pins of each set of motors (bit m−1 for motor m), in the port group's OUTSET.
  uint32_t masks[8];
};
extern StepPulseWords step_pulse_words;

// Starts both channels (after dma_init, before the step timer counts).
void step_pulses_start();

}  // namespace hmc::samd21
