// System Control Space (scs.h).
#include "scs.h"

#include "system.h"

namespace hmc::emu {

Scs::Scs(Chip& chip) : chip_(chip) {}

void Scs::reset() {
  enabled_ = sw_pending_ = 0;
  for (uint32_t& p : ipr_) p = 0;
  shpr2_ = shpr3_ = 0;
  systick_pending_ = pendsv_pending_ = false;
  active_.clear();
  csr_ = rvr_ = 0;
}

int Scs::priority(unsigned exception) const {
  if (exception == 2) return -2;  // NMI
  if (exception == kHardFault) return -1;
  if (exception == 11) return static_cast<int>(shpr2_ >> 30);
  if (exception == 14) return static_cast<int>((shpr3_ >> 22) & 3);
  if (exception == kSysTick) return static_cast<int>(shpr3_ >> 30);
  const unsigned line = exception - kFirstIrq;
  return static_cast<int>((ipr_[line / 4] >> (8 * (line % 4) + 6)) & 3);
}

// B1.5.4: the execution priority is the highest priority (lowest value) of the active
// exceptions, boosted to 0 by PRIMASK; 4 (lower than any configurable priority) in Thread mode.
int Scs::execution_priority(bool primask) const {
  int p = 4;
  for (const unsigned e : active_) p = priority(e) < p ? priority(e) : p;
  if (primask && p > 0) p = 0;
  return p;
}

bool Scs::pending(unsigned exception) const {
  if (exception == kSysTick) return systick_pending_;
  if (exception == 14) return pendsv_pending_;
  if (exception < kFirstIrq) return false;
  const unsigned line = exception - kFirstIrq;
  // B3.4.1: a peripheral's asserted line keeps its interrupt pending (level sensitive).
  return (sw_pending_ & (1u << line)) != 0 || chip_.irq_line(line);
}

unsigned Scs::ready_exception(bool primask) const {
  const int current = execution_priority(primask);
  unsigned best = 0;
  int best_priority = current;
  auto consider = [&](unsigned e) {
    if (!pending(e)) return;
    for (const unsigned a : active_) {
      if (a == e) return;  // already active: pending again only after its return
    }
    if (priority(e) < best_priority) {
      best_priority = priority(e);
      best = e;
    }
  };
  consider(14);
  consider(kSysTick);
  for (unsigned line = 0; line < Chip::kIrqLines; ++line) {
    if ((enabled_ & (1u << line)) != 0) consider(kFirstIrq + line);
  }
  return best;
}

void Scs::acknowledge(unsigned exception) {
  if (exception == kSysTick) systick_pending_ = false;
  if (exception == 14) pendsv_pending_ = false;
  if (exception >= kFirstIrq) sw_pending_ &= ~(1u << (exception - kFirstIrq));
  active_.push_back(exception);
}

void Scs::complete(unsigned exception) {
  for (auto it = active_.rbegin(); it != active_.rend(); ++it) {
    if (*it == exception) {
      active_.erase(std::next(it).base());
      break;
    }
  }
  chip_.irq_changed();
}

void Scs::pend(unsigned exception) {
  if (exception == kSysTick) systick_pending_ = true;
  if (exception == 14) pendsv_pending_ = true;
  if (exception >= kFirstIrq) sw_pending_ |= 1u << (exception - kFirstIrq);
  chip_.irq_changed();
}

// ---- SysTick (B3.3): counts CPU cycles down from RVR; COUNTFLAG on each 1 → 0 step, cleared by
// a read of CSR; a write to CVR clears it to 0, and the next cycle reloads RVR.

uint64_t Scs::systick_elapsed() const {
  const uint64_t cycles = chip_.cycles() - start_cycles_;
  return systick_ticks_ == systick_cycles_ ? cycles
                                           : mul_div(cycles, systick_ticks_, systick_cycles_);
}

uint64_t Scs::systick_zeros() const {
  if ((csr_ & 1) == 0) return zeros_seen_;
  const uint64_t elapsed = systick_elapsed();
  const uint64_t first = start_value_ != 0 ? start_value_ : systick_period();
  return elapsed < first ? 0 : 1 + (elapsed - first) / systick_period();
}

uint32_t Scs::systick_value() const {
  if ((csr_ & 1) == 0) return start_value_;
  const uint64_t elapsed = systick_elapsed();
  if (elapsed <= start_value_) return static_cast<uint32_t>(start_value_ - elapsed);
  const uint64_t into = (elapsed - start_value_ - 1) % systick_period();
  return static_cast<uint32_t>((rvr_ & 0xFFFFFF) - into);
}

uint64_t Scs::next_event_ps() const {
  if ((csr_ & 3) != 3) return UINT64_MAX;
  const uint64_t first = start_value_ != 0 ? start_value_ : systick_period();
  const uint64_t zero_tick = first + zeros_pended_ * systick_period();
  const uint64_t zero_cycle =
      start_cycles_ + (zero_tick * systick_cycles_ + systick_ticks_ - 1) / systick_ticks_;
  const uint64_t hz = chip_.cpu_hz();
  if (hz == 0) return UINT64_MAX;
  const uint64_t ahead = zero_cycle > chip_.cycles() ? zero_cycle - chip_.cycles() : 0;
  return chip_.now_ps() + ahead * Chip::kPsPerSecond / hz;
}

void Scs::advance(uint64_t) {
  if ((csr_ & 3) != 3) return;
  const uint64_t zeros = systick_zeros();
  if (zeros > zeros_pended_) {
    zeros_pended_ = zeros;
    pend(kSysTick);
  }
}

uint32_t Scs::read(uint32_t offset, unsigned size) {
  if (size != 4) {
    chip_.violation("System Control Space access of " + std::to_string(size) +
                    " bytes (ARMv6-M B3.1: word accesses only)");
    return 0;
  }
  switch (offset) {
    case 0x010: {
      const uint64_t zeros = systick_zeros();
      const bool flag = zeros > zeros_seen_;
      zeros_seen_ = zeros;
      return csr_ | (flag ? 1u << 16 : 0u);
    }
    case 0x014: return rvr_;
    case 0x018: return systick_value();
    case 0x01C: return 0;  // CALIB: no reference clock (NOREF 0? the SAMD21 gives none)
    case 0x100: case 0x180: return enabled_;
    case 0x200: case 0x280: {
      uint32_t p = sw_pending_;
      for (unsigned line = 0; line < Chip::kIrqLines; ++line) {
        if (chip_.irq_line(line)) p |= 1u << line;
      }
      return p;
    }
    case 0xD00: return 0x410CC601;  // CPUID: Cortex-M0+ r0p1 (SAMD21 datasheet 11.1.1)
    case 0xD04: {
      const unsigned pending_now = ready_exception(false);
      return active_exception() | (pending_now << 12) |
             (systick_pending_ ? 1u << 26 : 0u) | (pendsv_pending_ ? 1u << 28 : 0u);
    }
    case 0xD08: return vtor_;
    case 0xD0C: return 0xFA050000;
    case 0xD1C: return shpr2_;
    case 0xD20: return shpr3_;
    default:
      if (offset >= 0x400 && offset < 0x420) return ipr_[(offset - 0x400) / 4];
      return 0;  // SCR, CCR, SHCSR and the rest: reserved or read as zero here
  }
}

void Scs::write(uint32_t offset, uint32_t value, unsigned size) {
  if (size != 4) {
    chip_.violation("System Control Space access of " + std::to_string(size) +
                    " bytes (ARMv6-M B3.1: word accesses only)");
    return;
  }
  chip_.irq_changed();
  chip_.reschedule();
  switch (offset) {
    case 0x010: {
      const uint32_t old = csr_;
      if ((old & 1) != 0) {
        start_value_ = systick_value();
        start_cycles_ = chip_.cycles();
        zeros_seen_ = zeros_pended_ = 0;
      }
      csr_ = value & 7;
      if ((old & 1) == 0 && (csr_ & 1) != 0) {
        start_cycles_ = chip_.cycles();
        zeros_seen_ = zeros_pended_ = 0;
      }
      if ((csr_ & 4) == 0 && (csr_ & 1) != 0) {
        chip_.violation("SysTick on the external reference clock: the SAMD21 provides none");
      }
      return;
    }
    case 0x014: rvr_ = value & 0xFFFFFF; return;
    case 0x018:  // any write clears the counter and COUNTFLAG
      start_value_ = 0;
      start_cycles_ = chip_.cycles();
      zeros_seen_ = zeros_pended_ = 0;
      return;
    case 0x100: enabled_ |= value & 0x0FFFFFFF; return;
    case 0x180: enabled_ &= ~value; return;
    case 0x200: sw_pending_ |= value & 0x0FFFFFFF; return;
    case 0x280: sw_pending_ &= ~value; return;
    case 0xD04:
      if ((value & (1u << 25)) != 0) systick_pending_ = false;
      if ((value & (1u << 26)) != 0) systick_pending_ = true;
      if ((value & (1u << 27)) != 0) pendsv_pending_ = false;
      if ((value & (1u << 28)) != 0) pendsv_pending_ = true;
      return;
    case 0xD08: vtor_ = value & 0xFFFFFF80u; return;
    case 0xD0C:
      // B3.2.6: writes without VECTKEY 0x05FA are ignored; SYSRESETREQ asks for a reset.
      if ((value >> 16) == 0x05FA && (value & 4) != 0) chip_.request_reset(Pm::kCauseSystem);
      return;
    case 0xD1C: shpr2_ = value & 0xC0000000u; return;
    case 0xD20: shpr3_ = value & 0xC0C00000u; return;
    default:
      if (offset >= 0x400 && offset < 0x420) {
        ipr_[(offset - 0x400) / 4] = value & 0xC0C0C0C0u;
        return;
      }
      return;
  }
}

}  // namespace hmc::emu
