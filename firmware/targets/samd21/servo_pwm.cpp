// ServoPwm (servo_pwm.h). TCC setup: SAMD21 datasheet "TCC" (NPWM: the output goes high at the
// period start and low at the compare match; CCBx is copied to CCx at the period end). Pulse
// range: HARDWARE.md (Servos: 544-2400 µs, 20 ms period).
#include "servo_pwm.h"

#include "board.h"
#include "clocks.h"
#include "irq.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_system.h"
#include "regs_timer.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kTcc = tcc::kTcc0;
constexpr uint32_t kPrescalerDiv16 = 4;
constexpr uint32_t kCountsPerUs = board::kCpuHz / 16u / 1000000u;  // 3
constexpr uint32_t kPeriodCounts = 20000u * kCountsPerUs;          // 20 ms
constexpr uint16_t kMaxPulseUs = 2500;  // clamp: never near the period
// Bound of the wait in release(): each spin takes at least 4 cycles, so ≥ 3 ms at 48 MHz.
constexpr uint32_t kReleaseSpinLimit = 36000;
// A starting servo's pin is not handed over in the last 100 µs of a period: the counter read
// and the switch take a few µs with interrupts masked, far less than this.
constexpr uint32_t kHandOverMarginCounts = 100u * kCountsPerUs;

void sync(uint32_t bits) { wait_clear32(kTcc + tcc::kSyncBusy, bits); }

// The counter, synchronised (datasheet, TCC, "Synchronization": COUNT is read after a READSYNC
// command has completed).
uint32_t read_count() {
  r8(kTcc + tcc::kCtrlBSet) = tcc::kCmdReadSync;
  sync(tcc::kSyncCtrlB | tcc::kSyncCount);
  return r32(kTcc + tcc::kCount);
}

}  // namespace

void ServoPwm::init() {
  for (const board::Pin pin : board::servo::kPins) {
    pin_output(pin, false);
    pin_sense(pin);  // release() watches the pulse end
  }
  set32(pm::kApbCMask, pm::kApbCTcc0);
  clock_connect(gclk::kIdTcc0Tcc1, kGclkCpu);
  r32(kTcc + tcc::kCtrlA) = tcc::kSwRst;
  sync(tcc::kSyncSwRst);
  r32(kTcc + tcc::kCtrlA) = tcc::prescaler(kPrescalerDiv16);
  r32(kTcc + tcc::kWave) = tcc::kWaveNpwm;
  sync(tcc::kSyncWave);
  r32(kTcc + tcc::kPer) = kPeriodCounts - 1u;
  sync(tcc::kSyncPer);
  for (const uint32_t channel : board::servo::kChannels) {
    r32(kTcc + tcc::cc(channel)) = 0;
    sync(tcc::sync_cc(channel));
  }
  set32(kTcc + tcc::kCtrlA, tcc::kEnable);
  sync(tcc::kSyncEnable);
}

void ServoPwm::set_pulse(uint8_t servo, uint16_t pulse_us) {
  if (servo < 1 || servo > 2) return;
  const uint32_t index = servo - 1u;
  const uint32_t channel = board::servo::kChannels[index];
  const uint32_t counts = (pulse_us < kMaxPulseUs ? pulse_us : kMaxPulseUs) * kCountsPerUs;
  if (running_[index]) {
    r32(kTcc + tcc::ccb(channel)) = counts;  // applied at the next period start
    return;
  }
  // Not driving the pin yet: set the compare directly; service() hands the pin over once a
  // period has started with it and its pulse is over.
  r32(kTcc + tcc::cc(channel)) = counts;
  sync(tcc::sync_cc(channel));
  r32(kTcc + tcc::kIntFlag) = tcc::kIntOvf;
  counts_[index] = counts;
  period_seen_[index] = false;
  starting_[index] = true;
}

void ServoPwm::service() {
  if (!starting_[0] && !starting_[1]) return;
  if ((r32(kTcc + tcc::kIntFlag) & tcc::kIntOvf) != 0) {
    r32(kTcc + tcc::kIntFlag) = tcc::kIntOvf;
    for (uint32_t index = 0; index < 2; ++index) period_seen_[index] = period_seen_[index] || starting_[index];
  }
  for (uint32_t index = 0; index < 2; ++index) {
    if (!starting_[index] || !period_seen_[index]) continue;
    // Masked from the read to the switch, so no interrupt can delay the switch into the next
    // period.
    const uint32_t primask = irq_save();
    const uint32_t count = read_count();
    if (count >= counts_[index] && count < kPeriodCounts - kHandOverMarginCounts) {
      pin_function(board::servo::kPins[index], board::servo::kFunctions[index]);
      starting_[index] = false;
      running_[index] = true;
    }
    irq_restore(primask);
  }
}

void ServoPwm::release(uint8_t servo) {
  if (servo < 1 || servo > 2) return;
  const uint32_t index = servo - 1u;
  starting_[index] = false;  // its pin was never handed over: it is still the GPIO, low
  if (!running_[index]) return;
  // Wait for the pulse in progress to end (≤ 2.5 ms), so the last pulse is never cut short:
  // a shortened pulse is a command to another angle.
  const board::Pin pin = board::servo::kPins[index];
  for (uint32_t spins = 0; pin_read(pin) && spins < kReleaseSpinLimit; ++spins) {
  }
  pin_release(pin);  // back to the GPIO output, low
  running_[index] = false;
}

}  // namespace hmc::samd21
