// StepTimer (step_timer.h). TC registers: regs_timer.h; 32-bit mode pairs TC4 (master, whose
// registers and interrupt are used) with TC5 (SAMD21 datasheet, "TC", 32-bit counter mode).
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

uint32_t read_count() {
  r16(kTc + tc::kReadReq) = tc::kReadCount;
  sync();
  return r32(kTc + tc::kCount);
}

}  // namespace

void StepTimer::start() {
  set32(pm::kApbCMask, pm::kApbCTc4 | pm::kApbCTc5);
  clock_connect(gclk::kIdTc4Tc5, kGclkCpu);
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kSwRst);
  while ((r16(kTc + tc::kCtrlA) & tc::kSwRst) != 0) {
  }
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kMode32 | tc::prescaler(0));
  sync();
  r32(kTc + tc::kCc0) = 0xFFFFFFFFu;
  sync();
  r32(kTc + tc::kCc1) = 0xFFFFFFFFu;
  sync();
  step_pulses_start();  // MC0 raises nothing until the interrupt arms a step
  r8(kTc + tc::kIntFlag) = static_cast<uint8_t>(tc::kIntOvf | tc::kIntMc0);
  r8(kTc + tc::kIntEnSet) = static_cast<uint8_t>(tc::kIntOvf | tc::kIntMc0);
  high_ = 0;
  // SysTick free-running at the CPU clock, no interrupt: the step interrupt's stopwatch.
  r32(systick::kRvr) = 0xFFFFFFu;
  r32(systick::kCvr) = 0;
  r32(systick::kCsr) = systick::kEnableCpuClock;
  nvic_set_priority(irqn::kTc4, board::kPriorityStepTimer);
  nvic_unpend(irqn::kTc4);
  nvic_enable(irqn::kTc4);
  r16(kTc + tc::kCtrlA) = static_cast<uint16_t>(tc::kMode32 | tc::prescaler(0) | tc::kEnable);
  sync();
  // Both count the CPU clock (GCLK generator 0 undivided: clocks.h), SysTick down through 2^24
  // values (RVR 0xFFFFFF), the counter up: their sum stays fixed modulo 2^24. SysTick is read
  // first, the counter at its read request a few cycles later (the store, the request reaching
  // the timer's clock domain): the offset taken kBehindTicks lower than read puts the clock at
  // or behind the counter, never ahead (a wait on it never ends early).
  constexpr uint32_t kBehindTicks = 12;
  const uint32_t primask = irq_save();
  const uint32_t systick = r32(systick::kCvr);
  systick_offset_ = read_count() + systick - kBehindTicks;
  irq_restore(primask);
}

// An overflow not yet counted (its flag still set) belongs to this read when the low word has
// already wrapped; a low word still near the top was read before the wrap.
hal::Ticks StepTimer::now_masked() const {
  const uint32_t low = read_count();
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

// The compare belongs to the step interrupt, which enters by it with the STEP it prepared for
// that time (step_engine.h): the core asks only for an interrupt now (StepScheduler::kick), and
// an earlier entry than `when` is harmless (the interrupt steps only what is due).
void StepTimer::schedule(hal::Ticks when) {
  (void)when;
  nvic_pend(irqn::kTc4);
}

uint32_t StepTimer::take_step_interrupt() {
  const uint32_t flags = r8(kTc + tc::kIntFlag) & (tc::kIntOvf | tc::kIntMc0);
  r8(kTc + tc::kIntFlag) = static_cast<uint8_t>(flags);  // write 1 to clear
  if ((flags & tc::kIntOvf) != 0) high_ = high_ + 1u;
  return read_count();
}

}  // namespace hmc::samd21
