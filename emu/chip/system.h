// The SAMD21's system blocks: PM (bus clock masks, reset cause), SYSCTRL (oscillators, DFLL48M
// and their ready flags), GCLK (generators and peripheral channels), a minimal NVMCTRL and the
// WDT. Each rule cites the SAMD21 datasheet (DS40001882) section it follows.
#pragma once

#include <array>
#include <cstdint>

#include "chip.h"

namespace hmc::emu {

class Pm : public Peripheral {
 public:
  static constexpr uint32_t kApbAMask = 0x18, kApbBMask = 0x1C, kApbCMask = 0x20;
  // RCAUSE bits (datasheet 16.8.14): POR 0, BOD12 1, BOD33 2, EXT 4, WDT 5, SYST 6.
  static constexpr uint8_t kCausePowerOn = 1u << 0, kCauseWatchdog = 1u << 5,
                           kCauseSystem = 1u << 6;
  explicit Pm(Chip& chip);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  bool clocked(int mask_register, uint32_t bit) const {
    return (regs_.get(static_cast<uint32_t>(mask_register), 4) & bit) != 0;
  }
  void set_reset_cause(uint8_t cause) { regs_.set(0x38, cause, 1); }

 private:
  Chip& chip_;
  RegisterBytes regs_{0x40};
};

class Sysctrl : public Peripheral, public Timed {
 public:
  static constexpr uint64_t kOsc8mHz = 8000000, kDfllHz = 48000000, k32kHz = 32768;
  explicit Sysctrl(Chip& chip);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t) override {}
  uint64_t next_event_ps() const override { return UINT64_MAX; }
  // Frequency of a GCLK source (GENCTRL.SRC), 0 when it does not run.
  uint64_t source_hz(unsigned source) const;

 private:
  bool xosc32k_ready() const;
  bool dfll_ready() const;
  bool dfll_locked() const;
  Chip& chip_;
  RegisterBytes regs_{0x50};
  uint64_t xosc32k_ready_at_ = UINT64_MAX;  // start-up over (17.6.3)
  uint64_t closed_loop_at_ = UINT64_MAX;
};

class Gclk : public Peripheral {
 public:
  static constexpr unsigned kGenerators = 9, kChannels = 0x25;
  explicit Gclk(Chip& chip);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  uint64_t generator_hz(unsigned generator) const;
  uint64_t channel_hz(unsigned id) const;
  // Does an enabled generator take its clock from `source` (an on-demand request)?
  bool source_requested(unsigned source) const;
  void set_generator(unsigned id, unsigned source, uint32_t div, bool divsel);

 private:
  struct Generator {
    unsigned source = 0;
    bool enabled = false;
    bool divsel = false;
    uint32_t div = 0;
  };
  struct Channel {
    unsigned generator = 0;
    bool enabled = false;
  };
  Chip& chip_;
  std::array<Generator, kGenerators> generators_{};
  std::array<Channel, kChannels> channels_{};
  unsigned selected_channel_ = 0;
  unsigned selected_generator_ = 0;
  uint32_t gendiv_[kGenerators] = {};
};

// Minimal NVMCTRL: only what the image's start-up touches (CTRLB.RWS, PARAM, the READY flag).
// The full model — page buffer, erase and write commands, the SAM-BA path — comes from the
// bootloader work (emu/chip/nvmctrl.*); it replaces this block on the same Peripheral interface.
class NvmctrlMinimal : public Peripheral {
 public:
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  unsigned wait_states() const { return (regs_.get(0x04, 4) >> 1) & 0xF; }

 private:
  RegisterBytes regs_{0x30};
};

class Wdt : public Peripheral, public Timed {
 public:
  explicit Wdt(Chip& chip);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;

 private:
  bool enabled() const { return (regs_.get(0, 1) & 0x2) != 0; }
  uint64_t period_ps() const;
  void start_sync();
  Chip& chip_;
  RegisterBytes regs_{0x10};
  uint64_t cleared_at_ = 0;
  uint64_t sync_until_ = 0;
};

}  // namespace hmc::emu
