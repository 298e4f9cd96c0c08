// TC (16-bit TC3 for the buzzer; TC4+TC5 as one 32-bit counter for the step timer) and TCC0-2
// (TCC0: servo PWM). Counters are computed from virtual time, never ticked: the value at time t is
// the value at the last write plus the generic clock's periods since. SAMD21 datasheet chapters
// 30 (TC) and 31 (TCC).
#pragma once

#include <cstdint>
#include <string>

#include "chip.h"

namespace hmc::emu {

class Tc : public Peripheral, public DmaTimer {
 public:
  // `clock_id`: GCLK channel (0x1B TC3, 0x1C TC4/TC5); `dma_trigger_base`: the DMAC trigger
  // source of its OVF (MC0 and MC1 follow it).
  Tc(Chip& chip, std::string name, unsigned clock_id, unsigned dma_trigger_base);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;
  bool irq() const { return (intflag_ & inten_) != 0; }
  // Frequency mode (MFRQ) output: toggles per second / 2, or 0 when stopped.
  uint64_t output_hz() const;
  bool running() const { return enabled() && tick_hz() != 0; }
  void set_dma_watch(unsigned channels) override;
  unsigned dma_trigger_base() const override { return dma_trigger_base_; }
  unsigned compare_channels() const override { return 2; }

 private:
  bool enabled() const { return (ctrla_ & 2) != 0; }
  bool mode32() const { return ((ctrla_ >> 2) & 3) == 2; }
  bool mfrq() const { return ((ctrla_ >> 5) & 3) == 1; }
  uint64_t tick_hz() const;
  uint64_t modulus() const;  // count values per wrap
  uint64_t position(uint64_t now_ps) const;  // counts since the count was last set, plus it
  void rebase();
  void match_since(uint64_t landed);
  void reset_registers();
  uint64_t ps_at_position(uint64_t position) const;

  Chip& chip_;
  std::string name_;
  unsigned clock_id_;
  unsigned dma_trigger_base_;
  uint8_t dma_watch_ = 0;  // INTFLAG's MCx bits of the matches the DMAC listens to
  uint16_t ctrla_ = 0;
  uint8_t inten_ = 0, intflag_ = 0;
  uint32_t cc_[2] = {0, 0};
  uint32_t synced_count_ = 0;   // what a COUNT read returns (after a read request)
  bool continuous_read_ = false;
  uint64_t base_ps_ = 0;        // position = base_position_ + ticks since base_ps_
  uint64_t base_position_ = 0;
  uint64_t checked_position_ = 0;  // flags are up to date through this position
};

// A TCC as the image uses it: a single-slope counter from 0 to PER (NPWM, WAVE.WAVEGEN = 2), the
// compare channels' match flags and DMA triggers, their waveform outputs (WO[n] follows
// CC[n % channels] with WEXCTRL.OTMX = 0), double-buffered PER and CCx (PERB/CCBx copied at the
// period's end unless CTRLB.LUPD), OVF, and the READSYNC command that makes COUNT readable.
// Events (matches, wraps) are handled one at a time in time order, each with its exact time.
// Datasheet (DS40001882) chapter 31.
class Tcc : public Peripheral, public DmaTimer {
 public:
  static constexpr unsigned kMaxChannels = 4;
  // TCC`index` with a `width`-bit counter, `channels` compare channels and `outputs` waveform
  // outputs, clocked by GCLK channel `clock_id`; `dma_trigger_base`: its OVF trigger.
  Tcc(Chip& chip, unsigned index, unsigned width, unsigned channels, unsigned outputs,
      unsigned clock_id, unsigned dma_trigger_base);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override { return next_ps_; }
  bool irq() const { return (intflag_ & inten_) != 0; }
  // The level of waveform output WO[wo] now (low while disabled).
  bool output(unsigned wo);
  void set_dma_watch(unsigned channels) override;
  unsigned dma_trigger_base() const override { return dma_trigger_base_; }
  unsigned compare_channels() const override { return channels_; }

 private:
  bool enabled() const { return (ctrla_ & 2) != 0; }
  uint64_t tick_hz() const;
  uint64_t tick_at(uint64_t ps) const;  // counter ticks since the enable
  uint64_t ps_at(uint64_t tick) const;
  uint64_t period() const { return uint64_t{per_} + 1; }
  uint64_t next_tick() const;
  void step();
  void set_output(unsigned channel, bool level, uint64_t ps);
  void apply_buffers();
  void reset_registers();
  void plan_next();

  Chip& chip_;
  std::string name_;
  unsigned index_, channels_, outputs_, clock_id_, dma_trigger_base_;
  uint32_t mask_;  // the counter's width: COUNT, PER and CCx keep these bits
  unsigned dma_watch_ = 0;  // bit x: a DMAC channel is on MCx
  uint32_t ctrla_ = 0;
  uint8_t ctrlb_ = 0;  // DIR 0, LUPD 1, ONESHOT 2
  uint32_t wave_ = 0, per_ = 0, perb_ = 0;
  uint32_t cc_[kMaxChannels] = {}, ccb_[kMaxChannels] = {};
  uint32_t buffer_valid_ = 0;  // STATUS.PERBV (bit 7), CCBVx (bits 16-19)
  uint32_t inten_ = 0, intflag_ = 0;
  uint32_t count_ = 0;         // COUNT as the last READSYNC left it
  RegisterBytes other_{0x80};  // registers kept for reading back only
  uint64_t enable_ps_ = 0;
  uint64_t hz_ = 0;            // counter clock while enabled
  uint64_t period_start_ = 0;  // tick at which the current period began
  uint64_t processed_ = 0;     // events through this tick have been handled
  // CCx was last written at this tick: a match at or before it is not one (the value was
  // written at or below the count).
  uint64_t written_[kMaxChannels] = {};
  bool level_[kMaxChannels] = {};
  uint64_t next_ps_ = UINT64_MAX;  // the next match or wrap (nothing changes before it)
};

}  // namespace hmc::emu
