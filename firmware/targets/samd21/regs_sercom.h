// SAMD21 SERCOM registers in USART and SPI-master mode. Bases, IRQs, clock ids and the DMA
// triggers: HARDWARE.md (SERCOMn at 0x42000800 + n·0x400, IRQ 9+n, GCLK id 0x14+n, APBC bit
// 2+n, DMA TX trigger 2n+2); offsets and bits: SAMD21 datasheet, "SERCOM USART" and
// "SERCOM SPI" register summaries (the two modes share the layout used here).
#pragma once

#include <stdint.h>

namespace hmc::samd21::sercom {

constexpr uint32_t base(uint32_t n) { return 0x42000800u + n * 0x400u; }

// Offsets from base().
inline constexpr uint32_t kCtrlA = 0x00;
inline constexpr uint32_t kCtrlB = 0x04;
inline constexpr uint32_t kBaud = 0x0C;      // USART: 16-bit; SPI: 8-bit
inline constexpr uint32_t kIntEnClr = 0x14;  // 8-bit
inline constexpr uint32_t kIntEnSet = 0x16;  // 8-bit
inline constexpr uint32_t kIntFlag = 0x18;   // 8-bit
inline constexpr uint32_t kStatus = 0x1A;    // 16-bit
inline constexpr uint32_t kSyncBusy = 0x1C;  // 32-bit
inline constexpr uint32_t kData = 0x28;

// CTRLA (both modes).
inline constexpr uint32_t kSwRst = 1u << 0;
inline constexpr uint32_t kEnable = 1u << 1;
inline constexpr uint32_t kModeUsartInternalClock = 1u << 2;
inline constexpr uint32_t kModeSpiMaster = 3u << 2;
constexpr uint32_t txpo(uint32_t v) { return (v & 3u) << 16; }  // USART: 1 = TX on PAD2
constexpr uint32_t dopo(uint32_t v) { return (v & 3u) << 16; }  // SPI: 0 = DO PAD0 / SCK PAD1,
                                                                //      1 = DO PAD2 / SCK PAD3
constexpr uint32_t rxpo(uint32_t pad) { return (pad & 3u) << 20; }  // USART RX pad
constexpr uint32_t dipo(uint32_t pad) { return (pad & 3u) << 20; }  // SPI DI pad
inline constexpr uint32_t kSamprArithmetic16x = 0u << 13;
inline constexpr uint32_t kDordLsbFirst = 1u << 30;  // USART: LSB first; SPI: 0 = MSB first

// CTRLB.
inline constexpr uint32_t kTxEn = 1u << 16;  // USART
inline constexpr uint32_t kRxEn = 1u << 17;  // USART and SPI

// INTFLAG / INTEN bits.
inline constexpr uint32_t kIntDre = 1u << 0;
inline constexpr uint32_t kIntTxc = 1u << 1;
inline constexpr uint32_t kIntRxc = 1u << 2;

// STATUS (write 1 to clear): PERR 0, FERR 1, BUFOVF 2.
inline constexpr uint32_t kStatusErrors = 0x7;
inline constexpr uint32_t kStatusBufOvf = 1u << 2;

// SYNCBUSY.
inline constexpr uint32_t kSyncSwRst = 1u << 0;
inline constexpr uint32_t kSyncEnable = 1u << 1;
inline constexpr uint32_t kSyncCtrlB = 1u << 2;

// USART arithmetic baud with 16× oversampling: BAUD = 65536·(1 − 16·baud/f), rounded
// (HARDWARE.md: 115200 at 48 MHz → 63019).
constexpr uint16_t usart_baud(uint32_t f, uint32_t baud) {
  return static_cast<uint16_t>(
      65536u - ((65536ull * 16u * baud + f / 2u) / f));
}
// SPI master: BAUD = f/(2·fSCK) − 1 (HARDWARE.md: 500 kHz → 47).
constexpr uint8_t spi_baud(uint32_t f, uint32_t sck) {
  return static_cast<uint8_t>(f / (2u * sck) - 1u);
}
static_assert(usart_baud(48000000, 115200) == 63019, "HARDWARE.md worked value");
static_assert(spi_baud(48000000, 500000) == 47, "HARDWARE.md worked value");

}  // namespace hmc::samd21::sercom
