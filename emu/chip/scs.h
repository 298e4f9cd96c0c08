// The Cortex-M0+ System Control Space at 0xE000E000: SysTick, the NVIC (enable, pending,
// priority of the 28 SAMD21 lines) and the SCB (ICSR, VTOR, AIRCR, SHPR), plus the exception
// bookkeeping the CPU needs to take and return from exceptions: which exception is ready, which
// are active. ARMv6-M Architecture Reference Manual (DDI0419), B3.2-B3.4 and B1.5.
#pragma once

#include <cstdint>
#include <vector>

#include "chip.h"

namespace hmc::emu {

class Scs : public Peripheral, public Timed {
 public:
  static constexpr unsigned kHardFault = 3, kSysTick = 15, kFirstIrq = 16;
  explicit Scs(Chip& chip);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;

  uint32_t vtor() const { return vtor_; }
  void set_vtor(uint32_t vtor) { vtor_ = vtor; }
  // The exception that would preempt now (B1.5.4: lower priority value wins, then the lower
  // exception number), or 0.
  unsigned ready_exception(bool primask) const;
  void acknowledge(unsigned exception);  // entry: pending → active
  void complete(unsigned exception);     // return: leaves the active set
  unsigned active_exception() const { return active_.empty() ? 0 : active_.back(); }
  bool irq_enabled(unsigned line) const { return (enabled_ & (1u << line)) != 0; }
  void pend(unsigned exception);
  void reset();
  // SysTick counts `ticks` per `cycles` CPU cycles (the SAMD21: 1 per 1). hmc-emu-bench sets
  // 16384 per 1000 to stand for qemu's microbit under -icount shift=10: one instruction per
  // 1024 ns, SysTick at 16 MHz.
  void set_systick_rate(uint64_t ticks, uint64_t cycles) {
    systick_ticks_ = ticks;
    systick_cycles_ = cycles;
  }

 private:
  int priority(unsigned exception) const;
  int execution_priority(bool primask) const;
  bool pending(unsigned exception) const;
  uint64_t systick_period() const { return uint64_t{rvr_ & 0xFFFFFF} + 1; }
  uint64_t systick_zeros() const;  // zero crossings since the count (re)started
  uint32_t systick_value() const;
  uint64_t systick_elapsed() const;  // ticks since start_cycles_

  Chip& chip_;
  uint32_t enabled_ = 0;
  uint32_t sw_pending_ = 0;
  uint32_t ipr_[8] = {};
  uint32_t shpr2_ = 0, shpr3_ = 0;
  bool systick_pending_ = false, pendsv_pending_ = false;
  uint32_t vtor_ = 0;
  std::vector<unsigned> active_;
  // SysTick: counting from `start_cycles_` with value `start_value_`.
  uint32_t csr_ = 0, rvr_ = 0;
  uint64_t start_cycles_ = 0;
  uint32_t start_value_ = 0;
  uint64_t systick_ticks_ = 1, systick_cycles_ = 1;
  uint64_t zeros_seen_ = 0;     // COUNTFLAG: crossings already reported by a CSR read
  uint64_t zeros_pended_ = 0;   // TICKINT: crossings already turned into a pending SysTick
};

}  // namespace hmc::emu
