// The SAMD21 DMA controller: the LED strips' byte transfers from a RAM buffer to a SERCOM's data
// register, one beat per trigger, polled for completion (no interrupt; channels 0 and 1), and
// the STEP pulses' endless one-word transfers on the step timer's compares (step_pulses.h;
// channels 2 to 10). Channel registers are reached through the shared CHID selector, so every
// call belongs to the main loop (or to start-up, before interrupts are on).
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

inline constexpr uint32_t kDmaChannels = 11;

// Resets and enables the DMAC (every priority level); first, before any channel is started.
void dma_init();
// Starts channel `channel`: `count` bytes from `source` to the register at `destination`,
// paced by peripheral trigger `trigger`. The channel must be idle.
void dma_start(uint32_t channel, const uint8_t* source, uint16_t count, uint32_t destination,
               uint32_t trigger);
// True while the channel still has bytes to move.
bool dma_busy(uint32_t channel);
// Starts channel `channel` for ever: at each trigger `trigger`, one word from `source` (read at
// that moment) to the register at `destination`; its descriptor is linked to itself. `level`:
// the channel's arbitration level (0-3, higher served first).
void dma_start_endless_word(uint32_t channel, const volatile uint32_t* source, uint32_t destination,
                            uint32_t trigger, uint32_t level);

}  // namespace hmc::samd21
