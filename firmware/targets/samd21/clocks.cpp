// Clock setup (clocks.h). Sequence and values: HARDWARE.md (NVM wait states 1 at 48 MHz; DFLL48M
// closed loop ×1465 on the 32.768 kHz crystal through GCLK1, or the factory coarse value) and
// the SAMD21 datasheet, "SYSCTRL" (DFLL48M configuration order: DFLLCTRL written first with
// ONDEMAND cleared, then DFLLRDY waited before every further DFLL register write, DFLLMUL before
// closed-loop mode) and "GCLK".
//
// The CPU runs from OSC8M while the DFLL is configured: a bootloader may have left GCLK0 on the
// DFLL, and reconfiguring the clock the CPU runs on is not allowed. SysTick, counting 8 MHz CPU
// cycles, bounds the waits for the crystal and the lock.
#include "clocks.h"

#include "board.h"
#include "reg_access.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kDfllMultiplier = 1465;          // 1465 × 32 768 Hz = 48.005 MHz
constexpr uint32_t kDfllFineStart = 512;            // middle of the 10-bit fine range
constexpr uint32_t kDfllFineStep = 511;             // at most half the range (datasheet)
constexpr uint32_t kDfllCoarseStep = 31;
constexpr uint32_t kCrystalStartupCode = 4;         // ready flag after ~0.5 s
constexpr uint32_t kCrystalTimeoutMs = 1500;
constexpr uint32_t kLockTimeoutMs = 100;
constexpr uint32_t kOsc8mHz = 8000000;

void gclk_sync() { wait_clear8(gclk::kStatus, gclk::kSyncBusy); }

void dfll_sync() {
  while ((r32(sysctrl::kPclkSr) & sysctrl::kDfllRdy) == 0) {
  }
}

void generator(uint32_t id, uint32_t source, uint32_t div, bool divsel) {
  r32(gclk::kGenDiv) = gclk::gendiv(id, div);
  gclk_sync();
  r32(gclk::kGenCtrl) = gclk::genctrl(id, source, divsel);
  gclk_sync();
}

// Waits until every bit of `bits` is set in PCLKSR, at most `ms` milliseconds (CPU on OSC8M).
bool wait_ready(uint32_t bits, uint32_t ms) {
  r32(systick::kRvr) = kOsc8mHz / 1000u - 1u;
  r32(systick::kCvr) = 0;
  r32(systick::kCsr) = systick::kEnableCpuClock;
  for (;;) {
    if ((r32(sysctrl::kPclkSr) & bits) == bits) break;
    if (ms == 0) break;
    if ((r32(systick::kCsr) & systick::kCountFlag) != 0) --ms;  // reading clears the flag
  }
  r32(systick::kCsr) = 0;
  return (r32(sysctrl::kPclkSr) & bits) == bits;
}

// Starts the 32.768 kHz crystal oscillator unless it already runs; false when it does not start.
bool start_crystal() {
  const uint32_t running = sysctrl::kXosc32kEnable | sysctrl::kXosc32kXtalEn;
  if ((r16(sysctrl::kXosc32k) & running) == running &&
      (r32(sysctrl::kPclkSr) & sysctrl::kXosc32kRdy) != 0) {
    return true;
  }
  const uint32_t config =
      sysctrl::xosc32k_startup(kCrystalStartupCode) | sysctrl::kXosc32kXtalEn |
      sysctrl::kXosc32kEn32k;
  r16(sysctrl::kXosc32k) = static_cast<uint16_t>(config);
  r16(sysctrl::kXosc32k) = static_cast<uint16_t>(config | sysctrl::kXosc32kEnable);
  if (wait_ready(sysctrl::kXosc32kRdy, kCrystalTimeoutMs)) return true;
  r16(sysctrl::kXosc32k) = 0;
  return false;
}

// DFLL48M enabled in open loop at the factory coarse value.
// DFLLCTRL is written before the first wait: at reset ONDEMAND is set and nothing requests the
// DFLL, so its register interface is not clocked and DFLLRDY stays clear until a write clears
// ONDEMAND (silicon errata, DFLL48M; the Arduino core, Klipper and ASF do the same).
void dfll_open_loop(uint32_t coarse) {
  r16(sysctrl::kDfllCtrl) = static_cast<uint16_t>(sysctrl::kDfllEnable);  // ONDEMAND cleared
  dfll_sync();
  r32(sysctrl::kDfllVal) = sysctrl::dfll_val(coarse, kDfllFineStart);
  dfll_sync();
}

}  // namespace

void clock_connect(uint32_t id, uint32_t generator_id) {
  r16(gclk::kClkCtrl) = gclk::clkctrl(id, generator_id);
  gclk_sync();
}

ClockSource clocks_init() {
  // One flash wait state before the CPU goes above 24 MHz; all bus dividers at 1.
  r32(nvmctrl::kCtrlB) = (r32(nvmctrl::kCtrlB) & ~nvmctrl::kRwsMask) | nvmctrl::rws(1);
  r8(pm::kCpuSel) = 0;
  r8(pm::kApbASel) = 0;
  r8(pm::kApbBSel) = 0;
  r8(pm::kApbCSel) = 0;

  // CPU on OSC8M, undivided, while the DFLL changes.
  clear32(sysctrl::kOsc8m, sysctrl::kOsc8mPrescMask);
  while ((r32(sysctrl::kPclkSr) & sysctrl::kOsc8mRdy) == 0) {
  }
  generator(kGclkCpu, gclk::kSrcOsc8m, 1, false);

  uint32_t coarse = (r32(sysctrl::kOtpDfllCoarseWord) >> sysctrl::kOtpDfllCoarseShift) & 0x3Fu;
  if (coarse == 0x3F) coarse = 0x1F;  // an erased calibration word: take the middle
  dfll_open_loop(coarse);

  ClockSource source = ClockSource::kFactoryCalibrated;
  if (board::kTryCrystal32k && start_crystal()) {
    generator(kGclkDfllRef, gclk::kSrcXosc32k, 1, false);
    clock_connect(gclk::kIdDfll48mRef, kGclkDfllRef);
    r32(sysctrl::kDfllMul) = sysctrl::dfll_mul(kDfllMultiplier, kDfllFineStep, kDfllCoarseStep);
    dfll_sync();
    r16(sysctrl::kDfllCtrl) = static_cast<uint16_t>(
        sysctrl::kDfllEnable | sysctrl::kDfllModeClosed | sysctrl::kDfllWaitLock);
    dfll_sync();
    if (wait_ready(sysctrl::kDfllLckC | sysctrl::kDfllLckF, kLockTimeoutMs)) {
      source = ClockSource::kCrystalLocked;
    } else {
      dfll_open_loop(coarse);
    }
  }

  generator(kGclkCpu, gclk::kSrcDfll48m, 1, false);
  // Watchdog clock: OSCULP32K / 2^(4+1) = 1024 Hz. Switch filter clock: OSCULP32K itself.
  generator(kGclkWatchdog, gclk::kSrcOscUlp32k, 4, true);
  generator(kGclkSlow32k, gclk::kSrcOscUlp32k, 1, false);
  return source;
}

}  // namespace hmc::samd21
