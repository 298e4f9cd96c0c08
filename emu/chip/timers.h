// TC (16-bit TC3 for the buzzer; TC4+TC5 as one 32-bit counter for the step timer) and TCC0
// (servo PWM). Counters are computed from virtual time, never ticked: the value at time t is
// the value at the last write plus the generic clock's periods since. SAMD21 datasheet chapters
// 30 (TC) and 31 (TCC).
#pragma once

#include <cstdint>
#include <string>

#include "chip.h"

namespace hmc::emu {

class Tc : public Peripheral, public Timed {
 public:
  // `clock_id`: GCLK channel (0x1B TC3, 0x1C TC4/TC5).
  Tc(Chip& chip, std::string name, unsigned clock_id);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;
  bool irq() const { return (intflag_ & inten_) != 0; }
  // Frequency mode (MFRQ) output: toggles per second / 2, or 0 when stopped.
  uint64_t output_hz() const;
  bool running() const { return enabled() && tick_hz() != 0; }

 private:
  bool enabled() const { return (ctrla_ & 2) != 0; }
  bool mode32() const { return ((ctrla_ >> 2) & 3) == 2; }
  bool mfrq() const { return ((ctrla_ >> 5) & 3) == 1; }
  uint64_t tick_hz() const;
  uint64_t modulus() const;  // count values per wrap
  uint64_t position(uint64_t now_ps) const;  // counts since the count was last set, plus it
  void rebase();
  void reset_registers();

  Chip& chip_;
  std::string name_;
  unsigned clock_id_;
  uint16_t ctrla_ = 0;
  uint8_t inten_ = 0, intflag_ = 0;
  uint32_t cc_[2] = {0, 0};
  uint32_t synced_count_ = 0;   // what a COUNT read returns (after a read request)
  bool continuous_read_ = false;
  uint64_t base_ps_ = 0;        // position = base_position_ + ticks since base_ps_
  uint64_t base_position_ = 0;
  uint64_t checked_position_ = 0;  // flags are up to date through this position
};

class Tcc : public Peripheral {
 public:
  explicit Tcc(Chip& chip) : chip_(chip) {}
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  // Pulse width of compare channel `channel` in µs, and the period in µs (0 when stopped).
  uint32_t pulse_us(unsigned channel) const;
  uint32_t period_us() const;

 private:
  bool enabled() const { return (regs_.get(0, 4) & 2) != 0; }
  uint64_t tick_hz() const;
  Chip& chip_;
  RegisterBytes regs_{0x80};
};

}  // namespace hmc::emu
