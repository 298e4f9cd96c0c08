// STEP pulses by DMA (step_pulses.h).
#include "step_pulses.h"

#include "board.h"
#include "dma.h"
#include "regs_dmac.h"
#include "regs_port.h"
#include "regs_timer.h"

namespace hmc::samd21 {
namespace {

constexpr uint8_t kGroup = board::kDrivers[0].step.group;
static_assert(board::kDrivers[1].step.group == kGroup && board::kDrivers[2].step.group == kGroup,
              "every STEP pin in one port group: one OUTSET and one OUTCLR write (pin_map.h)");
static_assert(kDmaChannels > kStepEndDmaChannel, "dma.cpp's descriptor and write-back sections "
              "hold an entry for each channel used");

constexpr uint32_t kPortGroup = port::kBase + kGroup * port::kGroupStride;

struct Masks {
  uint32_t of[8];
};
constexpr Masks step_masks() {
  Masks m{};
  for (uint8_t motors = 0; motors < 8; ++motors) {
    for (uint8_t i = 0; i < 3; ++i) {
      if ((motors & (1u << i)) != 0) m.of[motors] |= 1u << board::kDrivers[i].step.number;
    }
  }
  return m;
}
constexpr Masks kMasks = step_masks();
// Every STEP pin, read by the DMAC at each CC1 match (RAM: the DMAC reads its source over the bus
// matrix).
volatile uint32_t step_clear_mask = kMasks.of[7];

}  // namespace

StepPulseWords step_pulse_words = {0, 0xFFFFFFFFu,
                                   {kMasks.of[0], kMasks.of[1], kMasks.of[2], kMasks.of[3],
                                    kMasks.of[4], kMasks.of[5], kMasks.of[6], kMasks.of[7]}};

void step_pulses_start() {
  step_pulse_words.set_mask = 0;
  dma_start_endless_word(kStepSetDmaChannel, &step_pulse_words.set_mask,
                         kPortGroup + port::kOutSet, dmac::kTriggerTc4Mc0, kStepDmaLevel);
  dma_start_endless_word(kStepClearDmaChannel, &step_clear_mask, kPortGroup + port::kOutClr,
                         dmac::kTriggerTc4Mc1, kStepDmaLevel);
  dma_start_endless_word(kStepEndDmaChannel, &step_pulse_words.end, tc::kTc4 + tc::kCc1,
                         dmac::kTriggerTc4Mc0, kStepDmaLevel);
}

}  // namespace hmc::samd21
