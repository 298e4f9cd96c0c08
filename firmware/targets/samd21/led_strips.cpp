// LedStrips (led_strips.h). SPI setup: SAMD21 datasheet "SERCOM SPI" (master, transmit only,
// BAUD = 48 MHz / (2 · 2.4 MHz) − 1 = 9); timing and byte order: HARDWARE.md (SK6812 RGBW).
#include "led_strips.h"

#include "clocks.h"
#include "dma.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_dmac.h"
#include "regs_sercom.h"
#include "regs_system.h"
#include "sk6812.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kSpiHz = 2400000;
static_assert(sercom::spi_baud(board::kCpuHz, kSpiHz) == 9, "2.4 MHz exactly");
static_assert(LedStrips::kFrameBytes <= 0xFFFF, "one DMA block");

uint8_t frames[2][LedStrips::kFrameBytes];

void init_sercom(const board::LedStripPins& pins) {
  const uint32_t base = sercom::base(pins.sercom);
  set32(pm::kApbCMask, pm::kApbCSercom0 << pins.sercom);
  clock_connect(gclk::kIdSercom0 + pins.sercom, kGclkCpu);
  r32(base + sercom::kCtrlA) = sercom::kSwRst;
  wait_clear32(base + sercom::kSyncBusy, sercom::kSyncSwRst);
  r32(base + sercom::kCtrlA) = sercom::kModeSpiMaster | sercom::dopo(pins.dopo);  // mode 0, MSB
  r32(base + sercom::kCtrlB) = 0;  // 8-bit, receiver off
  wait_clear32(base + sercom::kSyncBusy, sercom::kSyncCtrlB);
  r8(base + sercom::kBaud) = sercom::spi_baud(board::kCpuHz, kSpiHz);
  set32(base + sercom::kCtrlA, sercom::kEnable);
  wait_clear32(base + sercom::kSyncBusy, sercom::kSyncEnable);
  pin_output(pins.data, false);
  pin_function(pins.data, pins.function);
}

}  // namespace

void LedStrips::init() {  // the DMAC is on already (main: dma_init before the step timer)
  for (const board::LedStripPins& pins : board::kLedStrips) init_sercom(pins);
  for (uint8_t strip = 1; strip <= 2; ++strip) set_color(strip, 0, 0, 0, 0);
}

void LedStrips::set_color(uint8_t strip, uint8_t r, uint8_t g, uint8_t b, uint8_t w) {
  if (strip < 1 || strip > 2) return;
  Strip& s = strips_[strip - 1];
  s.rgbw[0] = sk6812::scale(r, board::kLedBrightness);
  s.rgbw[1] = sk6812::scale(g, board::kLedBrightness);
  s.rgbw[2] = sk6812::scale(b, board::kLedBrightness);
  s.rgbw[3] = sk6812::scale(w, board::kLedBrightness);
  s.waiting = true;
  service();
}

void LedStrips::service() {
  for (uint32_t index = 0; index < 2; ++index) {
    if (strips_[index].waiting && !dma_busy(board::kLedStrips[index].dma_channel)) start(index);
  }
}

void LedStrips::start(uint32_t index) {
  Strip& s = strips_[index];
  uint8_t* frame = frames[index];
  uint8_t led[sk6812::kSpiBytesPerLed];
  sk6812::encode_led(s.rgbw[0], s.rgbw[1], s.rgbw[2], s.rgbw[3], led);
  for (uint32_t i = 0; i < kDataBytes; i += sizeof(led)) {
    for (uint32_t j = 0; j < sizeof(led); ++j) frame[i + j] = led[j];
  }
  // The latch bytes after the data are zero from start-up and never written.
  s.waiting = false;
  const board::LedStripPins& pins = board::kLedStrips[index];
  dma_start(pins.dma_channel, frame, static_cast<uint16_t>(kFrameBytes),
            sercom::base(pins.sercom) + sercom::kData, dmac::sercom_tx_trigger(pins.sercom));
}

}  // namespace hmc::samd21
