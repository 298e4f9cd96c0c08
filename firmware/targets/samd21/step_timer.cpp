// StepTimer (step_timer.h). TC and TCC registers: regs_timer.h; 32-bit mode pairs TC4 (master,
// whose registers and interrupt are used) with TC5 (SAMD21 datasheet, "TC", 32-bit counter mode).
#include "step_timer.h"

#include "board.h"
#include "clocks.h"
#include "irq.h"
#include "reg_access.h"
#include "regs_system.h"
#include "regs_timer.h"
#include "step_pulses.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kTc = tc::kTc4;

void sync() { wait_clear8(kTc + tc::kStatus, tc::kSyncBusy); }


void tcc_sync(uint32_t base) {
  while (r32(base + tcc::kSyncBusy) != 0) {
  }
}

// The TCC's counter: READSYNC copies it into COUNT (datasheet "TCC", CTRLBSET.CMD).
uint32_t tcc_count(uint32_t base) {
  r8(base + tcc::kCtrlBSet) = tcc::kCmdReadSync;
  tcc_sync(base);
  return r32(base + tcc::kCount);
}

// A motor's TCC free-running at the CPU clock through its whole width: normal PWM (the only
// waveform whose outputs, routed to no pin, do nothing here) with PER at the top, CC0's match
// as its interrupt.
void start_tcc(const StepCompare& c) {
  r32(c.base + tcc::kCtrlA) = tcc::kSwRst;
  while ((r32(c.base + tcc::kCtrlA) & tcc::kSwRst) != 0) {
  }
  r32(c.base + tcc::kWave) = tcc::kWaveNpwm;
  r32(c.base + tcc::kPer) = c.count_mask;
  r32(c.base + c.cc0) = c.count_mask;
  r32(c.base + c.cc1) = c.count_mask;
  tcc_sync(c.base);
  r32(c.base + tcc::kIntFlag) = tcc::kIntMc0 | tcc::kIntMc1 | tcc::kIntOvf;
  r32(c.base + tcc::kIntEnSet) = tcc::kIntMc0;
  r32(c.base + tcc::kCtrlA) = tcc::prescaler(0) | tcc::kEnable;
  tcc_sync(c.base);
}

}  // namespace

void StepTimer::start() {
  set32(pm::kApbCMask, pm::kApbCTc4 | pm::kApbCTc5 | pm::kApbCTcc1 | pm::kApbCTcc2);
  clock_connect(gclk::kIdTc4Tc5, kGclkCpu);
  clock_connect(gclk::kIdTcc0Tcc1, kGclkCpu);  // as servo_pwm.cpp's TCC0
  clock_connect(gclk::kIdTcc2Tc3, kGclkCpu);   // as buzzer.cpp's TC3
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kSwRst);
  while ((r16(kTc + tc::kCtrlA) & tc::kSwRst) != 0) {
  }
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kMode32 | tc::prescaler(0));
  sync();
  r32(kTc + tc::kCc0) = 0xFFFFFFFFu;
  sync();
  r32(kTc + tc::kCc1) = 0xFFFFFFFFu;
  sync();
  step_pulses_start();  // MC0 raises nothing until an interrupt arms a step
  r8(kTc + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntOvf | tc::kIntMc0);
  r8(kTc + tc::kIntEnSet) = static_cast<uint8_t>(tc::kIntOvf | tc::kIntMc0);
  high_ = 0;
  // SysTick free-running at the CPU clock, no interrupt: the step interrupts' stopwatch.
  r32(systick::kRvr) = 0xFFFFFFu;
  r32(systick::kCvr) = 0;
  r32(systick::kCsr) = systick::kEnableCpuClock;
  for (const StepCompare& c : kStepCompares) {
    nvic_set_priority(c.irq, board::kPriorityStepTimer);
    nvic_unpend(c.irq);
    nvic_enable(c.irq);
  }
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kMode32 | tc::prescaler(0) | tc::kEnable);
  sync();
  start_tcc(kStepCompares[1]);
  start_tcc(kStepCompares[2]);
  // Both count the CPU clock (GCLK generator 0 undivided: clocks.h), SysTick down through 2^24
  // values (RVR 0xFFFFFF), the counter up: their sum stays fixed modulo 2^24. SysTick is read
  // first, the counter at its read request a few cycles later (the store, the request reaching
  // the timer's clock domain): the offset taken kBehindTicks lower than read puts the clock at
  // or behind the counter, never ahead (a wait on it never ends early).
  constexpr uint32_t kBehindTicks = 12;
  // The same sum, read the same way for each TCC (a register write reaching the timer's clock
  // domain, then its synchronisation), gives the lanes' offsets modulo 2^24: each is exact to
  // the difference between the two reads' latencies.
  const uint32_t primask = irq_save();
  const uint32_t systick = r32(systick::kCvr);
  const uint32_t clock_sum = read_low() + systick;
  systick_offset_ = clock_sum - kBehindTicks;
  for (uint8_t lane = 1; lane < 3; ++lane) {
    const uint32_t lane_systick = r32(systick::kCvr);
    step_lane_words[lane].offset = tcc_count(kStepCompares[lane].base) + lane_systick - clock_sum;
  }
  for (StepLaneWords& w : step_lane_words) w.systick_offset = systick_offset_;
  irq_restore(primask);
}

// An overflow not yet counted (its flag still set) belongs to this read when the low word has
// already wrapped; a low word still near the top was read before the wrap.
hal::Ticks StepTimer::now_masked() const {
  const uint32_t low = read_low();
  uint32_t high = high_;
  if ((r8(kTc + tc::kIntFlag) & tc::kIntOvf) != 0 && low < 0x80000000u) ++high;
  return (static_cast<hal::Ticks>(high) << 32) | low;
}

hal::Ticks StepTimer::now() const {
  const uint32_t primask = irq_save();
  const hal::Ticks t = now_masked();
  irq_restore(primask);
  return t;
}

// The compares belong to the step interrupts, each entering by its own with the STEP it prepared
// for that time (step_engine.h): the core asks only for the interrupts now (StepScheduler::kick,
// after marking the lanes it asks something of), and an entry with nothing asked of its lane
// only clears its flag.
void StepTimer::schedule(hal::Ticks when) {
  (void)when;
  r32(nvic::kIspr) = (1u << kStepCompares[0].irq) | (1u << kStepCompares[1].irq) |
                     (1u << kStepCompares[2].irq);
}

}  // namespace hmc::samd21
