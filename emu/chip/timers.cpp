// TC and TCC (timers.h).
#include "timers.h"

#include <algorithm>

#include "../board/board.h"
#include "dmac.h"

namespace hmc::emu {

using samd21::port_functions::Unit;

namespace {

// The first counter position after `from` whose value modulo `m` is `value` (< m): where a
// counter counting on from `from` next holds it.
uint64_t next_position_holding(uint64_t value, uint64_t from, uint64_t m) {
  return from + 1 + ((value + m - (from + 1) % m) % m);
}

// CTRLA.PRESCALER (30.8.1): DIV1, 2, 4, 8, 16, 64, 256, 1024.
constexpr uint64_t kPrescaler[8] = {1, 2, 4, 8, 16, 64, 256, 1024};
constexpr uint8_t kOvf = 1, kMc0 = 1u << 4, kMc1 = 1u << 5;
// Enable-protected CTRLA fields (30.8.1): MODE, WAVEGEN, PRESCALER, RUNSTDBY, PRESCSYNC.
constexpr uint16_t kCtrlAProtected = 0x3F7C;
constexpr unsigned kTc3ClockId = 0x1B;  // GCLK_TCC2_TC3: TC3 drives the buzzer's pin
}  // namespace

Tc::Tc(Chip& chip, std::string name, unsigned clock_id, unsigned dma_trigger_base)
    : chip_(chip), name_(std::move(name)), clock_id_(clock_id), dma_trigger_base_(dma_trigger_base) {}

void Tc::set_dma_watch(unsigned channels) {
  advance(chip_.now_ps());
  dma_watch_ = static_cast<uint8_t>((channels & 3) << 4);  // kMc0, kMc1
  chip_.reschedule();
}

// The time at which the count reaches `position` (its first picosecond).
uint64_t Tc::ps_at_position(uint64_t p) const {
  const uint64_t hz = tick_hz();
  if (p < base_position_) {  // a match behind a base a compare's write just moved (rebase)
    const Wide back = static_cast<Wide>(base_position_ - p) * Chip::kPsPerSecond / hz;
    return base_ps_ - static_cast<uint64_t>(back);
  }
  const Wide ps = static_cast<Wide>(p - base_position_) * Chip::kPsPerSecond + hz - 1;
  return base_ps_ + static_cast<uint64_t>(ps / hz);
}

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
  return (tick_hz() + modulus()) / (2 * modulus());  // rounded
}

// 30.6.2.5: MCx is set when the counter equals CCx; OVF when it wraps past its top.
void Tc::advance(uint64_t now_ps) {
  if (tick_hz() == 0) return;
  const uint64_t now = position(now_ps);
  const uint64_t m = modulus();
  if (now <= checked_position_) return;
  const uint64_t from = checked_position_;
  auto crossed = [&](uint64_t value) {  // some p in (from, now] with p mod m == value
    return next_position_holding(value, from, m) <= now;
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
  // 30.6.4.1 "DMA Operation": "Channel Match or Capture (MCx): for a compare channel, the request
  // is set on each compare match detection and cleared on next clock cycle." A channel the DMAC
  // listens to is an event (next_event_ps), so at most one match of it lies in (from, now];
  // the beats are handed over with their match's time, in time order (checked_position_ is
  // already `now`, so the PORT write a beat makes, which advances this timer first, finds
  // nothing new).
  const uint8_t watched = flags & dma_watch_ & (kMc0 | kMc1);
  if (watched == 0) return;
  uint64_t at[2] = {UINT64_MAX, UINT64_MAX};
  for (unsigned c = 0; c < 2; ++c) {
    if ((watched & (kMc0 << c)) == 0) continue;
    const uint64_t first = next_position_holding(cc_[c] % m, from, m);
    if (first + m <= now) {
      chip_.violation(name_ + ": two compare matches of a DMA trigger between two looks at the "
                      "timer (a period shorter than the emulator's step) are not modelled");
      return;
    }
    at[c] = ps_at_position(first);
  }
  const unsigned mc[2] = {dma_trigger_base_ + 1, dma_trigger_base_ + 2};
  if (at[0] == at[1]) {
    chip_.dmac().timer_trigger(mc, 2, at[0]);  // both at one tick: the DMAC's arbitration orders them
    return;
  }
  const unsigned first = at[1] < at[0] ? 1u : 0u;
  for (unsigned c : {first, 1u - first}) {
    if (at[c] != UINT64_MAX) chip_.dmac().timer_trigger(&mc[c], 1, at[c]);
  }
}

// 30.6.2.5: MCx is set when the counter equals CCx. A compare written by a DMAC beat that landed
// at counter position `landed`, before the counter was last looked at: a value the counter
// passed since the beat matched then, as on the chip, where the write takes effect when the
// beat lands (the DMAC, 30.6.4.1, is handed that match with its own time).
void Tc::match_since(uint64_t landed) {
  const uint64_t m = modulus();
  if (landed >= checked_position_) return;
  for (unsigned c = 0; c < 2; ++c) {
    const uint64_t first = next_position_holding(cc_[c] % m, landed, m);
    if (first > checked_position_) continue;
    const uint8_t flag = static_cast<uint8_t>(kMc0 << c);
    if ((flag & ~intflag_) != 0) {
      intflag_ |= flag;
      chip_.irq_changed();
    }
    if ((dma_watch_ & flag) != 0) {
      const unsigned trigger = dma_trigger_base_ + 1 + c;
      chip_.dmac().timer_trigger(&trigger, 1, ps_at_position(first));
    }
  }
}

uint64_t Tc::next_event_ps() const {
  const uint64_t hz = tick_hz();
  const uint8_t wanted = inten_ | dma_watch_;
  if (hz == 0 || (wanted & (kOvf | kMc0 | kMc1)) == 0) return UINT64_MAX;
  const uint64_t m = modulus();
  const uint64_t from = checked_position_;
  uint64_t next = UINT64_MAX;
  const uint64_t values[3] = {0, cc_[0] % m, cc_[1] % m};
  const uint8_t bits[3] = {kOvf, kMc0, kMc1};
  for (int i = 0; i < 3; ++i) {
    if ((wanted & bits[i]) == 0) continue;
    const uint64_t p = next_position_holding(values[i], from, m);
    next = p < next ? p : next;
  }
  return ps_at_position(next);
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
      if (clock_id_ == kTc3ClockId) chip_.board().tone_source_changed();
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
    // A DMAC beat is served at the CPU's next block boundary but lands at its own time
    // (chip.h, access_ps): the counter may have passed the value it writes since.
    const uint64_t landed = position(chip_.access_ps());
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
    } else {
      match_since(landed);
    }
  }
  if (clock_id_ == kTc3ClockId) chip_.board().tone_source_changed();
  chip_.irq_changed();
  chip_.reschedule();
}

// ---- TCC (datasheet chapter 31; register offsets and reset values from Microchip's register
// description): CTRLA 0x00, CTRLBCLR 0x04, CTRLBSET 0x05, SYNCBUSY 0x08, WEXCTRL 0x14, DRVCTRL
// 0x18, INTENCLR 0x24, INTENSET 0x28, INTFLAG 0x2C, STATUS 0x30, COUNT 0x34, PATT 0x38, WAVE 0x3C,
// PER 0x40, CC0-3 0x44-0x50, PERB 0x6C, CCB0-3 0x70-0x7C. TCC1 and TCC2 have CC0 and CC1 only.
namespace {
constexpr uint32_t kTccOvf = 1;
// INTFLAG.MCx: "This flag is set on a comparison match, or when the corresponding CCx register
// contains a valid capture value" (31.8, INTFLAG).
constexpr uint32_t mc(unsigned n) { return 1u << (16 + n); }
constexpr uint32_t kPerbv = 1u << 7;
constexpr uint32_t ccbv(unsigned n) { return 1u << (16 + n); }
constexpr uint8_t kLupd = 1u << 1;
constexpr uint32_t kWaveNpwm = 2;
}  // namespace

Tcc::Tcc(Chip& chip, unsigned index, unsigned width, unsigned channels, unsigned outputs,
         unsigned clock_id, unsigned dma_trigger_base)
    : chip_(chip), name_("TCC" + std::to_string(index)), index_(index), channels_(channels),
      outputs_(outputs), clock_id_(clock_id), dma_trigger_base_(dma_trigger_base),
      mask_(static_cast<uint32_t>((uint64_t{1} << width) - 1)) {
  reset_registers();
}

void Tcc::reset_registers() {
  ctrla_ = 0;
  ctrlb_ = 0;
  wave_ = 0;
  per_ = perb_ = mask_;  // PER/PERB reset: all ones, the counter's width used
  for (unsigned c = 0; c < kMaxChannels; ++c) cc_[c] = ccb_[c] = 0;
  buffer_valid_ = inten_ = intflag_ = count_ = 0;
  other_ = RegisterBytes(0x80);
  hz_ = 0;
  period_start_ = processed_ = 0;
  for (uint64_t& w : written_) w = 0;
  for (bool& l : level_) l = false;
  next_ps_ = UINT64_MAX;
}

uint64_t Tcc::tick_hz() const {
  return chip_.channel_hz(clock_id_) / kPrescaler[(ctrla_ >> 8) & 7];
}

uint64_t Tcc::tick_at(uint64_t ps) const {
  return hz_ == 0 || ps <= enable_ps_ ? 0 : mul_div(ps - enable_ps_, hz_, Chip::kPsPerSecond);
}

uint64_t Tcc::ps_at(uint64_t tick) const {
  return enable_ps_ + static_cast<uint64_t>((static_cast<Wide>(tick) * Chip::kPsPerSecond + hz_ - 1) / hz_);
}

bool Tcc::output(unsigned wo) {
  advance(chip_.now_ps());
  return enabled() && wo < outputs_ && level_[wo % channels_];
}

// The DMAC's channels changed, possibly from a beat at its own time (access_ps): the matches
// before it are served with the channels there were.
void Tcc::set_dma_watch(unsigned channels) {
  advance(chip_.access_ps());
  dma_watch_ = channels;
}

void Tcc::set_output(unsigned channel, bool level, uint64_t ps) {
  if (level_[channel] == level) return;
  level_[channel] = level;
  // Output matrix with WEXCTRL.OTMX = 0 (31.6.3.x "Waveform Extension", Output Matrix table):
  // WO[n] follows CC[n % channels] (TCC0: WO[n] and WO[n + 4] both follow CC[n]).
  for (unsigned wo = channel; wo < outputs_; wo += channels_) {
    chip_.board().peripheral_edge(Unit::kTcc, index_, wo, level, ps);
  }
}

// "Double Buffering" (31.6.2.6): at the UPDATE condition — the counter wrapping at TOP, in
// up-counting single-slope operation — each buffer whose valid flag is set is copied into its
// register and the flag cleared, unless CTRLB.LUPD locks the update.
void Tcc::apply_buffers() {
  if ((ctrlb_ & kLupd) != 0) return;
  if ((buffer_valid_ & kPerbv) != 0) per_ = perb_;
  for (unsigned c = 0; c < channels_; ++c) {
    if ((buffer_valid_ & ccbv(c)) != 0) cc_[c] = ccb_[c];
  }
  buffer_valid_ = 0;
}

// The tick of the next event: the wrap, or an earlier compare match of this period.
uint64_t Tcc::next_tick() const {
  uint64_t next = period_start_ + period();
  for (unsigned c = 0; c < channels_; ++c) {
    const uint64_t match = period_start_ + cc_[c];
    if (match > processed_ && match > written_[c] && match < next) next = match;
  }
  return next;
}

// Enabled means NPWM: enabling in another mode, or writing WAVE while enabled, stops the
// emulator (write()). A DMA beat an event triggers may write this TCC and so advance it to the
// beat's time first, re-entering here: each step() leaves the next event planned before it
// hands over its beats, so the events are handled one by one in time order.
void Tcc::advance(uint64_t now_ps) {
  while (now_ps >= next_ps_) step();
}

// "Single-Slope PWM Generation" (31.6.2.5): the counter counts from ZERO to TOP (PER), then wraps
// to ZERO, setting INTFLAG.OVF; in NPWM the waveform output is set at ZERO and cleared on the
// compare match with CCx (a CCx of 0 keeps it low; one above TOP keeps it high). "Compare
// Operations" (31.6.2.5): the counter is continuously compared to each CCx; a match sets
// INTFLAG.MCx. A CCx of 0 equals the count at each wrap (not at the enable, where the count
// starts rather than reaches 0): its flag is set then, with OVF. A compare value written at or
// below the count (written_) does not match until the next period: the output stays as it is.
void Tcc::step() {
  const uint64_t tick = next_tick();
  const uint64_t ps = ps_at(tick);
  const uint64_t end = period_start_ + period();
  unsigned matched = 0;  // bit x: MCx
  if (tick == end) {
    intflag_ |= kTccOvf;
    apply_buffers();
    period_start_ = end;
    for (unsigned c = 0; c < channels_; ++c) {
      set_output(c, cc_[c] != 0, ps);
      if (cc_[c] == 0) matched |= 1u << c;
    }
  } else {
    for (unsigned c = 0; c < channels_; ++c) {
      if (period_start_ + cc_[c] != tick || tick <= written_[c]) continue;
      matched |= 1u << c;
      set_output(c, false, ps);
    }
  }
  processed_ = tick;
  for (unsigned c = 0; c < channels_; ++c) {
    if ((matched & (1u << c)) != 0) intflag_ |= mc(c);
  }
  chip_.irq_changed();
  plan_next();
  // "DMA Operation" (31.6.4.x): "Match or Capture (MCx): for a compare channel, the request is
  // set on each compare match detection". The DMAC's channels on these matches move their beats,
  // stamped with the match's time.
  unsigned triggers[kMaxChannels];
  unsigned count = 0;
  for (unsigned c = 0; c < channels_; ++c) {
    if ((matched & dma_watch_ & (1u << c)) != 0) triggers[count++] = dma_trigger_base_ + 1 + c;
  }
  if (count != 0) chip_.dmac().timer_trigger(triggers, count, ps);
}

void Tcc::plan_next() {
  next_ps_ = enabled() && hz_ != 0 ? ps_at(next_tick()) : UINT64_MAX;
}

uint32_t Tcc::read(uint32_t offset, unsigned size) {
  advance(chip_.now_ps());
  RegisterBytes view = other_;
  view.set(0x00, ctrla_, 4);
  view.set(0x04, ctrlb_, 1);
  view.set(0x05, ctrlb_, 1);
  view.set(0x08, 0, 4);  // SYNCBUSY: each synchronised write's delay is charged as a stall
  view.set(0x24, inten_, 4);
  view.set(0x28, inten_, 4);
  view.set(0x2C, intflag_, 4);
  view.set(0x30, buffer_valid_ | (enabled() ? 0u : 1u), 4);  // STATUS.STOP while disabled
  view.set(0x34, count_, 4);
  view.set(0x3C, wave_, 4);
  view.set(0x40, per_, 4);
  for (unsigned c = 0; c < channels_; ++c) view.set(0x44 + 4 * c, cc_[c], 4);
  view.set(0x6C, perb_, 4);
  for (unsigned c = 0; c < channels_; ++c) view.set(0x70 + 4 * c, ccb_[c], 4);
  return view.get(offset, size);
}

void Tcc::write(uint32_t offset, uint32_t value, unsigned size) {
  // A DMAC beat writes at its own time (chip.h, access_ps), the CPU now.
  const uint64_t now_ps = chip_.access_ps();
  advance(now_ps);
  RegisterBytes w(0x80);
  w.set(offset, value, size);
  const uint64_t sync_hz = chip_.channel_hz(clock_id_);
  const auto stall = [&] {
    if (sync_hz != 0) chip_.charge_stall(5, sync_hz);  // write-synchronised (31.6.8)
  };
  if (touches(offset, size, 0x00, 4)) {
    RegisterBytes view(4);
    view.set(0, ctrla_, 4);
    view.set(offset, value, size);
    const uint32_t v = view.get(0, 4);
    if ((v & 1) != 0) {  // SWRST: every register to its reset value, the TCC disabled (31.8.1)
      for (unsigned c = 0; c < channels_; ++c) set_output(c, false, now_ps);
      reset_registers();
      stall();
      chip_.irq_changed();
      chip_.reschedule();
      return;
    }
    if (enabled() && ((v ^ ctrla_) & ~3u) != 0) {
      chip_.violation("write to " + name_ + " CTRLA's enable-protected fields while enabled "
                      "(datasheet 31.8.1)");
      return;
    }
    const bool was = enabled();
    ctrla_ = v;
    if (!was && enabled()) {
      hz_ = tick_hz();
      if (hz_ == 0) {
        chip_.violation(name_ + " enabled without its generic clock (its GCLK channel off; "
                        "datasheet 31.5.3)");
        return;
      }
      if ((wave_ & 7) != kWaveNpwm) {
        chip_.violation(name_ + " waveform modes other than NPWM are not modelled (WAVE.WAVEGEN " +
                        std::to_string(wave_ & 7) + ")");
        return;
      }
      // The counter starts from COUNT (0 after a reset) when enabled (31.6.2.3).
      enable_ps_ = now_ps;
      period_start_ = processed_ = 0;
      for (uint64_t& written : written_) written = 0;
      for (unsigned c = 0; c < channels_; ++c) set_output(c, cc_[c] != 0, now_ps);
    } else if (was && !enabled()) {
      for (unsigned c = 0; c < channels_; ++c) set_output(c, false, now_ps);
    }
    stall();
  }
  if (touches(offset, size, 0x04, 1)) ctrlb_ &= static_cast<uint8_t>(~w.get(0x04, 1));
  if (touches(offset, size, 0x05, 1)) {
    const uint8_t v = static_cast<uint8_t>(w.get(0x05, 1));
    ctrlb_ |= static_cast<uint8_t>(v & 0x1F);
    const unsigned command = v >> 5;
    if ((ctrlb_ & 1) != 0 || (ctrlb_ & 4) != 0) {
      chip_.violation(name_ + " down-counting and one-shot operation (CTRLB.DIR, ONESHOT) are not "
                      "modelled");
      return;
    }
    stall();
    if (command == 4) {
      // READSYNC (31.8.3): COUNT is synchronised for reading; the bus waits for it (above), and
      // the counter may have wrapped meanwhile.
      advance(chip_.access_ps());
      if (enabled()) count_ = static_cast<uint32_t>(tick_at(chip_.access_ps()) - period_start_) & mask_;
    } else if (command == 3) {
      apply_buffers();  // UPDATE: the buffers now, as at a period's end
      for (uint64_t& written : written_) written = tick_at(now_ps);
    } else if (command != 0) {
      chip_.violation(name_ + " CTRLBSET.CMD " + std::to_string(command) +
                      " (RETRIGGER/STOP) is not modelled");
      return;
    }
  }
  if (touches(offset, size, 0x14, 4) || touches(offset, size, 0x18, 4) || touches(offset, size, 0x38, 2)) {
    if (w.get(offset, size) != 0) {
      chip_.violation(name_ + " WEXCTRL, DRVCTRL and PATT (output matrix, dead time, inversion, "
                      "patterns) are not modelled: written non-zero");
      return;
    }
  }
  if (touches(offset, size, 0x24, 4)) inten_ &= ~w.get(0x24, 4);
  if (touches(offset, size, 0x28, 4)) inten_ |= w.get(0x28, 4);
  if (touches(offset, size, 0x2C, 4)) intflag_ &= ~w.get(0x2C, 4);  // write 1 to clear
  if (touches(offset, size, 0x34, 4)) {
    stall();
    const uint64_t now = tick_at(now_ps);
    const uint32_t v = w.get(0x34, 4) & mask_;
    period_start_ = now >= v ? now - v : 0;
    processed_ = now;
  }
  if (touches(offset, size, 0x3C, 4)) {
    if (enabled()) {
      chip_.violation("write to " + name_ + " WAVE while enabled (datasheet 31.8.11: "
                      "enable-protected)");
      return;
    }
    wave_ = w.get(0x3C, 4);
    stall();
  }
  // PER and CCx written directly take effect at once; PERB and CCBx wait for the period's end
  // ("Double Buffering", 31.6.2.6). Their bits above the counter's width do not exist (TCC2:
  // 16 bits).
  if (touches(offset, size, 0x40, 4)) {
    per_ = w.get(0x40, 4) & mask_;
    stall();
  }
  for (unsigned c = 0; c < channels_; ++c) {
    if (touches(offset, size, 0x44 + 4 * c, 4)) {
      const uint64_t at = tick_at(now_ps);
      const uint32_t v = w.get(0x44 + 4 * c, 4) & mask_;
      if (enabled() && at < processed_) {
        // A DMAC beat, served at its own time a few cycles ahead of the CPU's, has had this TCC
        // handle its events up to then (processed_; a wrap among them moved period_start_). The
        // new value is modelled unless it would have matched in between, in the period the
        // write lands in.
        const uint64_t start = at >= period_start_ ? period_start_ : period_start_ - period();
        if (start + v > at && start + v <= processed_) {
          chip_.violation(name_ + ": a CC" + std::to_string(c) + " write that matches before "
                          "the timer's last handled event is not modelled");
          return;
        }
      }
      cc_[c] = v;
      written_[c] = at;
      stall();
    }
    if (touches(offset, size, 0x70 + 4 * c, 4)) {
      ccb_[c] = w.get(0x70 + 4 * c, 4) & mask_;
      buffer_valid_ |= ccbv(c);
      stall();
    }
  }
  if (touches(offset, size, 0x6C, 4)) {
    perb_ = w.get(0x6C, 4) & mask_;
    buffer_valid_ |= kPerbv;
    stall();
  }
  plan_next();
  for (uint32_t o = offset; o < offset + size; ++o) {
    const bool modelled = o < 0x0C || (o >= 0x24 && o < 0x38) || (o >= 0x3C && o < 0x54) || o >= 0x6C;
    if (!modelled) other_.set(o, w.get(o, 1), 1);
  }
  chip_.irq_changed();
  chip_.reschedule();
}

}  // namespace hmc::emu
