// TC and TCC (timers.h).
#include "timers.h"

#include "../board/board.h"

namespace hmc::emu {
namespace {
// CTRLA.PRESCALER (30.8.1): DIV1, 2, 4, 8, 16, 64, 256, 1024.
constexpr uint64_t kPrescaler[8] = {1, 2, 4, 8, 16, 64, 256, 1024};
constexpr uint8_t kOvf = 1, kMc0 = 1u << 4, kMc1 = 1u << 5;
// Enable-protected CTRLA fields (30.8.1): MODE, WAVEGEN, PRESCALER, RUNSTDBY, PRESCSYNC.
constexpr uint16_t kCtrlAProtected = 0x3F7C;
}  // namespace

Tc::Tc(Chip& chip, std::string name, unsigned clock_id)
    : chip_(chip), name_(std::move(name)), clock_id_(clock_id) {}

void Tc::reset_registers() {
  ctrla_ = 0;
  inten_ = intflag_ = 0;
  cc_[0] = cc_[1] = 0;
  synced_count_ = 0;
  continuous_read_ = false;
  base_ps_ = chip_.now_ps();
  base_position_ = checked_position_ = 0;
}

uint64_t Tc::tick_hz() const {
  if (!enabled()) return 0;
  return chip_.channel_hz(clock_id_) / kPrescaler[(ctrla_ >> 8) & 7];
}

uint64_t Tc::modulus() const {
  if (mfrq()) return uint64_t{cc_[0]} + 1;  // MFRQ: the counter restarts after CC0 (30.6.2.6)
  return mode32() ? (uint64_t{1} << 32) : (uint64_t{1} << 16);
}

uint64_t Tc::position(uint64_t now_ps) const {
  const uint64_t hz = tick_hz();
  if (hz == 0 || now_ps <= base_ps_) return base_position_;
  return base_position_ + mul_div(now_ps - base_ps_, hz, Chip::kPsPerSecond);
}

// The new base is the last whole tick, not now: dropping the fraction of a tick at every
// rebase (each CCx write: the step interrupt writes one a step) made the counter lose half a
// tick a write on average, 0.05 % of the step rate at 20 us a step.
void Tc::rebase() {
  const uint64_t hz = tick_hz();
  const uint64_t now_ps = chip_.now_ps();
  if (hz == 0 || now_ps <= base_ps_) {
    base_position_ = position(now_ps);
    base_ps_ = now_ps > base_ps_ ? now_ps : base_ps_;
    return;
  }
  const uint64_t ticks = mul_div(now_ps - base_ps_, hz, Chip::kPsPerSecond);
  base_position_ += ticks;
  base_ps_ += mul_div(ticks, Chip::kPsPerSecond, hz);
}

uint64_t Tc::output_hz() const {
  if (!running() || !mfrq()) return 0;
  return tick_hz() / (2 * modulus());
}

// 30.6.2.5: MCx is set when the counter equals CCx; OVF when it wraps past its top.
void Tc::advance(uint64_t now_ps) {
  if (tick_hz() == 0) return;
  const uint64_t now = position(now_ps);
  const uint64_t m = modulus();
  if (now <= checked_position_) return;
  const uint64_t from = checked_position_;
  auto crossed = [&](uint64_t value) {  // some p in (from, now] with p mod m == value
    const uint64_t first = from + 1 + ((value + m - (from + 1) % m) % m);
    return first <= now;
  };
  uint8_t flags = 0;
  if (crossed(0)) flags |= kOvf;
  if (crossed(cc_[0] % m)) flags |= kMc0;
  if (crossed(cc_[1] % m)) flags |= kMc1;
  checked_position_ = now;
  if ((flags & ~intflag_) != 0) {
    intflag_ |= flags;
    chip_.irq_changed();
  }
}

uint64_t Tc::next_event_ps() const {
  const uint64_t hz = tick_hz();
  if (hz == 0 || (inten_ & (kOvf | kMc0 | kMc1)) == 0) return UINT64_MAX;
  const uint64_t m = modulus();
  const uint64_t from = checked_position_;
  uint64_t next = UINT64_MAX;
  const uint64_t values[3] = {0, cc_[0] % m, cc_[1] % m};
  const uint8_t bits[3] = {kOvf, kMc0, kMc1};
  for (int i = 0; i < 3; ++i) {
    if ((inten_ & bits[i]) == 0) continue;
    const uint64_t p = from + 1 + ((values[i] + m - (from + 1) % m) % m);
    next = p < next ? p : next;
  }
  // Time at which position reaches `next`.
  const Wide ps = static_cast<Wide>(next - base_position_) * Chip::kPsPerSecond + hz - 1;
  return base_ps_ + static_cast<uint64_t>(ps / hz);
}

uint32_t Tc::read(uint32_t offset, unsigned size) {
  advance(chip_.now_ps());
  RegisterBytes view(0x20);
  view.set(0x00, ctrla_, 2);
  view.set(0x0C, inten_, 1);
  view.set(0x0D, inten_, 1);
  view.set(0x0E, intflag_, 1);
  if (continuous_read_) {
    synced_count_ = static_cast<uint32_t>(position(chip_.now_ps()) % modulus());
  }
  // COUNT returns the value of the last read synchronisation (30.6.6 "Synchronization"): a
  // read without a read request gets a stale value, as on the chip.
  if (mode32()) {
    view.set(0x10, synced_count_, 4);
    view.set(0x18, cc_[0], 4);
    view.set(0x1C, cc_[1], 4);
  } else {
    view.set(0x10, synced_count_, 2);
    view.set(0x18, cc_[0], 2);
    view.set(0x1A, cc_[1], 2);
  }
  // STATUS (0x0F): SLAVE 4 for TC5 in 32-bit mode is not modelled; SYNCBUSY reads 0.
  return view.get(offset, size);
}

void Tc::write(uint32_t offset, uint32_t value, unsigned size) {
  advance(chip_.now_ps());
  RegisterBytes view(0x20);
  view.set(0x00, ctrla_, 2);
  view.set(offset, value, size);
  const uint64_t sync_hz = chip_.channel_hz(clock_id_) ? chip_.channel_hz(clock_id_) : 1;
  if (touches(offset, size, 0x00, 2)) {
    const uint16_t v = static_cast<uint16_t>(view.get(0, 2));
    if ((v & 1) != 0) {
      reset_registers();
      chip_.irq_changed();
      chip_.reschedule();
      return;
    }
    if (enabled() && ((v ^ ctrla_) & kCtrlAProtected) != 0) {
      chip_.violation("write to " + name_ + " CTRLA's enable-protected fields while enabled "
                      "(datasheet 30.8.1)");
      return;
    }
    if (((v ^ ctrla_) & 2) != 0) {
      if ((v & 2) != 0 && chip_.channel_hz(clock_id_) == 0) {
        chip_.violation(name_ + " enabled without its generic clock (datasheet 30.6.2.1)");
        return;
      }
      rebase();
      ctrla_ = v;
      base_ps_ = chip_.now_ps();
      checked_position_ = base_position_;
      chip_.charge_stall(5, sync_hz);  // ENABLE synchronises (30.6.6)
    } else {
      ctrla_ = v;
    }
  }
  if (offset == 0x02 && size == 2) {  // READREQ alone: no timing or interrupt changes
    const uint16_t v = static_cast<uint16_t>(value);
    continuous_read_ = (v & (1u << 14)) != 0;
    if ((v & (1u << 15)) != 0 && (v & 0x1F) == 0x10) {
      // 30.6.6: the read request synchronises COUNT into the APB domain; the bus waits
      // 5 to 6 GCLK_TC periods plus 2 to 3 APB periods. Charged as 6 + 3.
      chip_.charge_stall(6, sync_hz);
      chip_.charge_cycles(3);
      synced_count_ = static_cast<uint32_t>(position(chip_.now_ps()) % modulus());
    }
    return;
  }
  RegisterBytes w(0x20);
  w.set(offset, value, size);
  if (touches(offset, size, 0x0C, 1)) inten_ &= static_cast<uint8_t>(~w.get(0x0C, 1));
  if (touches(offset, size, 0x0D, 1)) inten_ |= static_cast<uint8_t>(w.get(0x0D, 1));
  if (touches(offset, size, 0x0E, 1)) intflag_ &= static_cast<uint8_t>(~w.get(0x0E, 1));
  if (touches(offset, size, 0x10, mode32() ? 4 : 2)) {
    chip_.charge_stall(5, sync_hz);
    rebase();
    base_position_ = checked_position_ = w.get(0x10, mode32() ? 4 : 2);
  }
  if (touches(offset, size, 0x18, 8)) {
    chip_.charge_stall(5, sync_hz);  // CCx writes synchronise (30.6.6)
    rebase();
    if (mode32()) {
      if (touches(offset, size, 0x18, 4)) cc_[0] = w.get(0x18, 4);
      if (touches(offset, size, 0x1C, 4)) cc_[1] = w.get(0x1C, 4);
    } else {
      if (touches(offset, size, 0x18, 2)) cc_[0] = w.get(0x18, 2);
      if (touches(offset, size, 0x1A, 2)) cc_[1] = w.get(0x1A, 2);
    }
    // In MFRQ the modulus changed: restart the bookkeeping at the current count.
    if (mfrq()) {
      base_position_ %= modulus();
      checked_position_ = base_position_;
    }
  }
  chip_.irq_changed();
  chip_.reschedule();
}

// ---- TCC0: CTRLA 0x00 (ENABLE 1, PRESCALER 10:8), SYNCBUSY 0x08, WAVE 0x3C, PER 0x40,
// CC0-3 0x44-0x50, PERB 0x6C, CCB0-3 0x70-0x7C (datasheet 31.8). Buffered values (PERB, CCBx)
// are copied at the period's end (31.6.2.6); here at once — the pulse in progress is not cut.

uint64_t Tcc::tick_hz() const {
  return chip_.channel_hz(0x1A) / kPrescaler[(regs_.get(0, 4) >> 8) & 7];
}

uint32_t Tcc::pulse_us(unsigned channel) const {
  const uint64_t hz = tick_hz();
  if (!enabled() || hz == 0) return 0;
  return static_cast<uint32_t>(uint64_t{regs_.get(0x44 + 4 * channel, 4)} * 1000000 / hz);
}

uint32_t Tcc::period_us() const {
  const uint64_t hz = tick_hz();
  if (!enabled() || hz == 0) return 0;
  return static_cast<uint32_t>((uint64_t{regs_.get(0x40, 4)} + 1) * 1000000 / hz);
}

uint32_t Tcc::read(uint32_t offset, unsigned size) {
  regs_.set(0x08, 0, 4);  // SYNCBUSY: each write's delay is charged as a stall
  return regs_.get(offset, size);
}

void Tcc::write(uint32_t offset, uint32_t value, unsigned size) {
  if (touches(offset, size, 0x00, 4)) {
    RegisterBytes view(4);
    view.set(0, regs_.get(0, 4), 4);
    view.set(offset, value, size);
    const uint32_t v = view.get(0, 4);
    if ((v & 1) != 0) {
      regs_ = RegisterBytes(0x80);
      regs_.set(0x40, 0xFFFFFF, 4);  // PER reset (SVD: all ones, 24 bits used)
      return;
    }
    if (enabled() && ((v ^ regs_.get(0, 4)) & ~3u) != 0) {
      chip_.violation("write to TCC0 CTRLA's enable-protected fields while enabled "
                      "(datasheet 31.8.1)");
      return;
    }
  }
  if (touches(offset, size, 0x3C, 4) && enabled()) {
    chip_.violation("write to TCC0 WAVE while enabled (datasheet 31.8.11: enable-protected)");
    return;
  }
  regs_.set(offset, value, size);
  for (unsigned channel = 0; channel < 4; ++channel) {
    if (touches(offset, size, 0x70 + 4 * channel, 4)) {
      regs_.set(0x44 + 4 * channel, regs_.get(0x70 + 4 * channel, 4), 4);
    }
  }
  if (touches(offset, size, 0x6C, 4)) regs_.set(0x40, regs_.get(0x6C, 4), 4);
  const uint64_t hz = chip_.channel_hz(0x1A);
  if (hz != 0) chip_.charge_stall(5, hz);
  chip_.board().servos_changed();
}

}  // namespace hmc::emu
