// STEP pulses by DMA (step_pulses.h).
#include "step_pulses.h"

#include "board.h"
#include "dma.h"
#include "regs_dmac.h"
#include "regs_port.h"
#include "step_timer.h"

namespace hmc::samd21 {
namespace {

constexpr uint8_t kGroup = board::kDrivers[0].step.group;
static_assert(board::kDrivers[1].step.group == kGroup && board::kDrivers[2].step.group == kGroup,
              "every STEP pin in one port group: the DMA writes one OUTSET and one OUTCLR "
              "(pin_map.h)");
static_assert(kDmaChannels >= kStepFirstDmaChannel + 3 * kStepDmaChannelsPerLane,
              "dma.cpp's descriptor and write-back sections hold an entry for each channel used");

constexpr uint32_t kPortGroup = port::kBase + kGroup * port::kGroupStride;

constexpr uint32_t pin_mask(uint8_t lane) { return 1u << board::kDrivers[lane].step.number; }

}  // namespace

StepLaneWords step_lane_words[3] = {{0, 0, pin_mask(0), 0, 0}, {0, 0, pin_mask(1), 0, 0},
                                    {0, 0, pin_mask(2), 0, 0}};

void step_pulses_start() {
  for (uint8_t lane = 0; lane < 3; ++lane) {
    StepLaneWords& w = step_lane_words[lane];
    const StepCompare& compare = kStepCompares[lane];
    const uint32_t channel = kStepFirstDmaChannel + kStepDmaChannelsPerLane * lane;
    w.set_mask = 0;
    dma_start_endless_word(channel, &w.set_mask, kPortGroup + port::kOutSet, compare.trigger_mc0,
                           kStepDmaLevel);
    dma_start_endless_word(channel + 1, &w.end, compare.base + compare.cc1, compare.trigger_mc0,
                           kStepDmaLevel);
    dma_start_endless_word(channel + 2, &w.pin, kPortGroup + port::kOutClr, compare.trigger_mc1,
                           kStepDmaLevel);
  }
}

}  // namespace hmc::samd21
