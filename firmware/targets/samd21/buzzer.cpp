// Buzzer (buzzer.h). TC setup: SAMD21 datasheet "TC" (MFRQ: the counter restarts at CC0 and WO[0]
// toggles there, so f = f_clk / (2 · prescaler · (CC0 + 1))).
#include "buzzer.h"

#include "board.h"
#include "clocks.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_system.h"
#include "regs_timer.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kTc = tc::kTc3;
constexpr uint32_t kDiv8 = 3;   // 3 MHz half-periods: 46 Hz .. 20 kHz in 16 bits
constexpr uint32_t kDiv64 = 5;  // below 46 Hz

void sync() { wait_clear8(kTc + tc::kStatus, tc::kSyncBusy); }

void stop_counter() {
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(r16(kTc + tc::kCtrlA) & ~tc::kEnable);
  sync();
}

}  // namespace

void Buzzer::init() {
  pin_output(board::buzzer::kPin, false);
  set32(pm::kApbCMask, pm::kApbCTc3);
  clock_connect(gclk::kIdTcc2Tc3, kGclkCpu);
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kSwRst);
  while ((r16(kTc + tc::kCtrlA) & tc::kSwRst) != 0) {
  }
}

void Buzzer::tone(uint16_t hz, uint16_t ms) {
  silence();
  stop_at_ = clock_.now() + static_cast<hal::Ticks>(ms) * (board::kCpuHz / 1000u);
  if (hz == 0) return;
  const uint32_t half_period_clock = board::kCpuHz / 2u;
  uint32_t prescaler = kDiv8;
  uint32_t top = half_period_clock / 8u / hz;
  if (top > 0x10000u) {
    prescaler = kDiv64;
    top = half_period_clock / 64u / hz;
  }
  if (top > 0x10000u) top = 0x10000u;
  if (top < 2u) top = 2u;
  r16(kTc + tc::kCtrlA) =
      static_cast<uint16_t>(tc::kMode16 | tc::kWaveMfrq | tc::prescaler(prescaler));
  sync();
  r16(kTc + tc::kCount) = 0;
  sync();
  r16(kTc + tc::kCc0) = static_cast<uint16_t>(top - 1u);
  sync();
  pin_function(board::buzzer::kPin, board::buzzer::kFunction);
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(r16(kTc + tc::kCtrlA) | tc::kEnable);
  sync();
  sounding_ = true;
}

void Buzzer::service() {
  if (sounding_ && clock_.now() >= stop_at_) silence();
}

void Buzzer::silence() {
  if (!sounding_) return;
  pin_release(board::buzzer::kPin);  // the GPIO output, low
  stop_counter();
  sounding_ = false;
}

}  // namespace hmc::samd21
