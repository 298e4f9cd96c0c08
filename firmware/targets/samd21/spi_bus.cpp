// SpiBus (spi_bus.h). SPI master setup: SAMD21 datasheet "SERCOM SPI"; frame, mode, select
// polarity and timing: HARDWARE.md (DRV8711: 16 bits MSB first, mode 0, CS active high, a write
// takes effect when CS falls, CS inactive ≥ 100 ns between accesses).
#include "spi_bus.h"

#include "board.h"
#include "clocks.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_sercom.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kBase = sercom::base(board::driver_spi::kSercom);

// ~10 cycles at 48 MHz (≈ 200 ns): select setup and hold, and the gap between accesses.
inline void short_delay() {
  __asm__ volatile("nop\n\tnop\n\tnop\n\tnop\n\tnop\n\tnop\n\tnop\n\tnop\n\tnop\n\tnop");
}

uint8_t exchange(uint8_t out) {
  while ((r8(kBase + sercom::kIntFlag) & sercom::kIntDre) == 0) {
  }
  r32(kBase + sercom::kData) = out;
  while ((r8(kBase + sercom::kIntFlag) & sercom::kIntRxc) == 0) {
  }
  return static_cast<uint8_t>(r32(kBase + sercom::kData));
}

}  // namespace

void SpiBus::init() {
  set32(pm::kApbCMask, pm::kApbCSercom0 << board::driver_spi::kSercom);
  clock_connect(gclk::kIdSercom0 + board::driver_spi::kSercom, kGclkCpu);

  r32(kBase + sercom::kCtrlA) = sercom::kSwRst;
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncSwRst);
  // Mode 0 (CPOL 0, CPHA 0), MSB first (DORD 0), SPI frame.
  r32(kBase + sercom::kCtrlA) = sercom::kModeSpiMaster | sercom::dopo(board::driver_spi::kDopo) |
                                sercom::dipo(board::driver_spi::kDiPad);
  r32(kBase + sercom::kCtrlB) = sercom::kRxEn;  // 8-bit characters
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncCtrlB);
  r8(kBase + sercom::kBaud) = sercom::spi_baud(board::kCpuHz, board::driver_spi::kSckHz);

  // A pull-up on MISO keeps the line defined while no driver answers; harmless for a
  // push-pull output.
  pin_input(board::driver_spi::kMiso, true);
  pin_function(board::driver_spi::kMiso, board::driver_spi::kMisoFunction);
  pin_function(board::driver_spi::kMosi, board::driver_spi::kMosiFunction);
  pin_function(board::driver_spi::kSck, board::driver_spi::kSckFunction);

  set32(kBase + sercom::kCtrlA, sercom::kEnable);
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncEnable);
}

uint16_t SpiBus::transfer16(uint8_t chip, uint16_t word) {
  if (chip < 1 || chip > 3) return 0;
  const board::Pin cs = board::kDrivers[chip - 1].cs;
  pin_set(cs, true);
  short_delay();
  const uint8_t high = exchange(static_cast<uint8_t>(word >> 8));
  const uint8_t low = exchange(static_cast<uint8_t>(word));
  short_delay();
  pin_set(cs, false);
  short_delay();
  return static_cast<uint16_t>((high << 8) | low);
}

}  // namespace hmc::samd21
