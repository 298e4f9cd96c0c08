// The SAMD21 DMA controller as the LED strips use it: byte transfers from a RAM buffer to a
// peripheral's data register, one beat per peripheral trigger, polled for completion (no
// interrupt). Channel registers are reached through the shared CHID selector, so every call
// belongs to the main loop.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

inline constexpr uint32_t kDmaChannels = 2;

void dma_init();
// Starts channel `channel`: `count` bytes from `source` to the register at `destination`,
// paced by peripheral trigger `trigger`. The channel must be idle.
void dma_start(uint32_t channel, const uint8_t* source, uint16_t count, uint32_t destination,
               uint32_t trigger);
// True while the channel still has bytes to move.
bool dma_busy(uint32_t channel);

}  // namespace hmc::samd21
