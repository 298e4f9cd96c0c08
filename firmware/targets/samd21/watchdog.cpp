// Watchdog (watchdog.h). Registers: SAMD21 datasheet "WDT" (CONFIG.PER 6 = 512 clock periods;
// CLEAR takes the key 0xA5; writes synchronise to the WDT clock, STATUS.SYNCBUSY).
#include "watchdog.h"

#include "clocks.h"
#include "reg_access.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

constexpr uint8_t kPeriod512 = 6;

void sync() { wait_clear8(wdt::kStatus, wdt::kSyncBusy); }

}  // namespace

void watchdog_start() {
  set32(pm::kApbAMask, pm::kApbAWdt);
  clock_connect(gclk::kIdWdt, kGclkWatchdog);
  r8(wdt::kCtrl) = 0;  // CONFIG may be written only while disabled
  sync();
  r8(wdt::kConfig) = kPeriod512;
  sync();
  r8(wdt::kCtrl) = static_cast<uint8_t>(wdt::kEnable);
  sync();
}

void watchdog_kick() {
  if ((r8(wdt::kStatus) & wdt::kSyncBusy) != 0) return;  // a kick is already on its way
  r8(wdt::kClear) = wdt::kClearKey;
}

}  // namespace hmc::samd21
