// PM, SYSCTRL, GCLK and WDT (system.h).
#include "system.h"

#include "hex.h"
#include "reset_values.h"

namespace hmc::emu {

// ---- PM -------------------------------------------------------------------------------------

Pm::Pm(Chip& chip) : chip_(chip) {
  regs_.load(reset::kPm);
  if (chip.options().after_bootloader) {
    // The bootloader's USB port needs its clocks: SERCOMs stay masked, as after reset.
    regs_.set(kApbBMask, regs_.get(kApbBMask, 4) | (1u << 5), 4);
  }
}

uint32_t Pm::read(uint32_t offset, unsigned size) { return regs_.get(offset, size); }

void Pm::write(uint32_t offset, uint32_t value, unsigned size) {
  if (touches(offset, size, 0x38, 1)) {
    chip_.violation("write to PM RCAUSE, a read-only register (datasheet 16.8.14)");
    return;
  }
  regs_.set(offset, value, size);
  chip_.reschedule();  // CPUSEL may change the CPU clock
}

// ---- SYSCTRL --------------------------------------------------------------------------------
// Register map: datasheet 17.7 (PCLKSR 0x0C, XOSC32K 0x14, OSC8M 0x20, DFLLCTRL 0x24,
// DFLLVAL 0x28, DFLLMUL 0x2C).

namespace {
constexpr uint32_t kPclkSr = 0x0C, kXosc32k = 0x14, kOsc8m = 0x20, kDfllCtrl = 0x24;
constexpr uint32_t kDfllEnable = 1u << 1, kDfllMode = 1u << 2, kDfllOnDemand = 1u << 7;
// XOSC32K start-up times by STARTUP code, datasheet 37.13.3 (Table "XOSC32K start-up time"):
// 122 µs, 1068 µs, 62.6 ms, 125 ms, 500 ms, 1 s, 2 s, 4 s.
constexpr uint64_t kXosc32kStartupUs[8] = {122, 1068, 62592, 125092, 500092, 1000092, 2000092,
                                           4000092};
// DFLL48M closed-loop lock time. Guess: the datasheet gives no figure for this configuration;
// 200 µs stands for "a few reference periods of coarse and fine search".
constexpr uint64_t kDfllLockPs = 200 * 1000000ull;
}  // namespace

Sysctrl::Sysctrl(Chip& chip) : chip_(chip) {
  regs_.load(reset::kSysctrl);
  if (chip.options().after_bootloader) {
    // What the Arduino/UF2 bootloaders leave: DFLL48M on (ONDEMAND cleared; closed loop on the
    // crystal when there is one), the crystal running.
    if (chip.options().crystal) {
      regs_.set(kXosc32k, 0x060E, 2);  // ENABLE, XTALEN, EN32K, AAMPEN, STARTUP 6
      xosc32k_ready_at_ = 0;
      regs_.set(kDfllCtrl, kDfllEnable | kDfllMode, 2);
      closed_loop_at_ = 0;
    } else {
      regs_.set(kDfllCtrl, kDfllEnable, 2);
    }
  }
}

bool Sysctrl::xosc32k_ready() const {
  const uint32_t ctrl = regs_.get(kXosc32k, 2);
  if (!chip_.options().crystal || (ctrl & 0x6) != 0x6) return false;
  return chip_.now_ps() >= xosc32k_ready_at_;
}

// Datasheet 17.6.7.1.1 and silicon errata "DFLL48M" (the DFLL must be requested before it is
// configured, "write a zero to the DFLL ONDEMAND bit in DFLLCTRL before configuring"): with
// ONDEMAND set and no generator requesting the DFLL, its register interface is not clocked and
// DFLLRDY stays clear.
bool Sysctrl::dfll_ready() const {
  const uint32_t ctrl = regs_.get(kDfllCtrl, 2);
  return (ctrl & kDfllOnDemand) == 0 || chip_.gclk().source_requested(7);
}

bool Sysctrl::dfll_locked() const {
  return closed_loop_at_ != UINT64_MAX && xosc32k_ready() &&
         chip_.channel_hz(0) != 0 && chip_.now_ps() >= closed_loop_at_ + kDfllLockPs;
}

uint64_t Sysctrl::source_hz(unsigned source) const {
  switch (source) {
    case 3:  // OSCULP32K (datasheet 15.8.4, GENCTRL.SRC)
      return k32kHz;
    case 5:  // XOSC32K
      return xosc32k_ready() ? k32kHz : 0;
    case 6:  // OSC8M, PRESC 9:8 divides by 2^PRESC (17.8.11)
      return kOsc8mHz >> ((regs_.get(kOsc8m, 4) >> 8) & 3);
    case 7: {  // DFLL48M: running once enabled (open loop: the factory coarse value ≈ 48 MHz)
      const uint32_t ctrl = regs_.get(kDfllCtrl, 2);
      return (ctrl & kDfllEnable) != 0 ? kDfllHz : 0;
    }
    default:
      return 0;
  }
}

uint32_t Sysctrl::read(uint32_t offset, unsigned size) {
  if (touches(offset, size, kPclkSr, 4)) {
    uint32_t status = 1u << 3;  // OSC8MRDY: OSC8M runs from reset
    if (xosc32k_ready()) status |= 1u << 1;
    if (dfll_ready()) status |= 1u << 4;
    if (dfll_locked()) status |= (1u << 6) | (1u << 7);
    regs_.set(kPclkSr, status, 4);
  }
  return regs_.get(offset, size);
}

void Sysctrl::write(uint32_t offset, uint32_t value, unsigned size) {
  // Errata "DFLL48M": a DFLL register write while its interface is not clocked freezes the
  // device. Stop rather than model the freeze.
  const bool dfll_register = touches(offset, size, 0x24, 0x10);
  if (dfll_register && !dfll_ready() && !touches(offset, size, kDfllCtrl, 2)) {
    chip_.violation("write to a DFLL48M register while DFLLRDY is clear (silicon errata DFLL48M: "
                    "this freezes the device)");
    return;
  }
  const uint32_t old_xosc = regs_.get(kXosc32k, 2);
  const uint32_t old_dfll = regs_.get(kDfllCtrl, 2);
  regs_.set(offset, value, size);
  if (touches(offset, size, kPclkSr, 4)) regs_.set(kPclkSr, 0, 4);  // status is read-only
  const uint32_t xosc = regs_.get(kXosc32k, 2);
  if ((xosc & 0x2) == 0) {
    xosc32k_ready_at_ = UINT64_MAX;
  } else if ((old_xosc & 0x2) == 0) {
    xosc32k_ready_at_ = chip_.now_ps() + kXosc32kStartupUs[(xosc >> 8) & 7] * 1000000ull;
  }
  const uint32_t dfll = regs_.get(kDfllCtrl, 2);
  if ((dfll & (kDfllEnable | kDfllMode)) != (kDfllEnable | kDfllMode)) {
    closed_loop_at_ = UINT64_MAX;
  } else if ((old_dfll & (kDfllEnable | kDfllMode)) != (kDfllEnable | kDfllMode)) {
    closed_loop_at_ = chip_.now_ps();
  }
  chip_.reschedule();
}

// ---- GCLK -----------------------------------------------------------------------------------
// Datasheet 15.8: CTRL 0x00, STATUS 0x01, CLKCTRL 0x02 (ID 5:0, GEN 11:8, CLKEN 14), GENCTRL
// 0x04 (ID 3:0, SRC 12:8, GENEN 16, DIVSEL 20), GENDIV 0x08 (ID 3:0, DIV 23:8). A read of
// CLKCTRL, GENCTRL or GENDIV returns the entry last selected by an 8-bit write of its ID.

Gclk::Gclk(Chip& chip) : chip_(chip) {
  // Reset (15.6.2.1, 15.8.4): generator 0 on OSC8M feeds the CPU; generator 2 on OSCULP32K
  // feeds the WDT channel.
  generators_[0] = Generator{6, true, false, 0};
  generators_[2] = Generator{3, true, false, 0};
  channels_[3] = Channel{2, true};
  if (chip.options().after_bootloader) {
    generators_[0] = Generator{7, true, false, 0};
    if (chip.options().crystal) {
      generators_[1] = Generator{5, true, false, 0};
      channels_[0] = Channel{1, true};
    }
  }
}

void Gclk::set_generator(unsigned id, unsigned source, uint32_t div, bool divsel) {
  generators_[id] = Generator{source, true, divsel, div};
}

uint64_t Gclk::generator_hz(unsigned generator) const {
  if (generator >= kGenerators) return 0;
  const Generator& g = generators_[generator];
  if (!g.enabled) return 0;
  const uint64_t hz = chip_.sysctrl().source_hz(g.source);
  if (g.divsel) return hz >> (g.div + 1);
  return g.div > 1 ? hz / g.div : hz;
}

uint64_t Gclk::channel_hz(unsigned id) const {
  if (id >= kChannels || !channels_[id].enabled) return 0;
  return generator_hz(channels_[id].generator);
}

bool Gclk::source_requested(unsigned source) const {
  for (const Generator& g : generators_) {
    if (g.enabled && g.source == source) return true;
  }
  return false;
}

uint32_t Gclk::read(uint32_t offset, unsigned size) {
  uint32_t bytes[3] = {0, 0, 0};  // words 0x00, 0x04, 0x08
  const Channel& c = channels_[selected_channel_];
  bytes[0] = (selected_channel_ | c.generator << 8 | (c.enabled ? 1u << 14 : 0u)) << 16;
  const Generator& g = generators_[selected_generator_];
  bytes[1] = selected_generator_ | g.source << 8 | (g.enabled ? 1u << 16 : 0u) |
             (g.divsel ? 1u << 20 : 0u);
  bytes[2] = selected_generator_ | gendiv_[selected_generator_] << 8;
  // STATUS.SYNCBUSY reads 0: every write's synchronisation is charged as a bus stall instead.
  RegisterBytes view(12);
  for (uint32_t i = 0; i < 3; ++i) view.set(4 * i, bytes[i], 4);
  return view.get(offset, size);
}

void Gclk::write(uint32_t offset, uint32_t value, unsigned size) {
  // Writes to CLKCTRL, GENCTRL, GENDIV synchronise to the generator's clock (15.6.6): charged
  // as a stall of 5 periods of the slowest clock involved, at least 32 kHz.
  RegisterBytes view(12);
  view.set(offset, value, size);
  if (touches(offset, size, 0x02, 2)) {
    const uint32_t v = view.get(0x02, 2);
    selected_channel_ = v & 0x3F;
    if (selected_channel_ >= kChannels) {
      chip_.violation("GCLK CLKCTRL.ID " + std::to_string(selected_channel_) + " does not exist");
      return;
    }
    if (size == 2 || offset == 0x03) {
      channels_[selected_channel_] = Channel{(v >> 8) & 0xF, (v & (1u << 14)) != 0};
      chip_.charge_stall(5, 32768);
    }
  }
  if (touches(offset, size, 0x04, 4)) {
    const uint32_t v = view.get(0x04, 4);
    selected_generator_ = v & 0xF;
    if (selected_generator_ >= kGenerators) {
      chip_.violation("GCLK GENCTRL.ID " + std::to_string(selected_generator_) + " does not exist");
      return;
    }
    if (size == 4) {
      Generator& g = generators_[selected_generator_];
      g.source = (v >> 8) & 0x1F;
      g.enabled = (v & (1u << 16)) != 0;
      g.divsel = (v & (1u << 20)) != 0;
      g.div = gendiv_[selected_generator_];
      chip_.charge_stall(5, 32768);
    }
  }
  if (touches(offset, size, 0x08, 4)) {
    const uint32_t v = view.get(0x08, 4);
    selected_generator_ = v & 0xF;
    if (selected_generator_ < kGenerators && size == 4) {
      gendiv_[selected_generator_] = (v >> 8) & 0xFFFF;
      generators_[selected_generator_].div = gendiv_[selected_generator_];
    }
  }
  chip_.reschedule();
}

// ---- WDT ------------------------------------------------------------------------------------
// Datasheet 18.8: CTRL 0x00 (ENABLE 1, WEN 2, ALWAYSON 7), CONFIG 0x01 (PER 3:0), STATUS 0x07
// (SYNCBUSY 7), CLEAR 0x08. Time-out period: 8 << PER cycles of GCLK_WDT (18.8.2).

Wdt::Wdt(Chip& chip) : chip_(chip) { regs_.load(reset::kWdt); }

uint64_t Wdt::period_ps() const {
  const uint64_t hz = chip_.channel_hz(3);
  if (hz == 0) return UINT64_MAX;
  const uint64_t cycles = 8ull << (regs_.get(1, 1) & 0xF);
  return cycles * Chip::kPsPerSecond / hz;
}

// Writes synchronise to GCLK_WDT (18.6.5): SYNCBUSY for about 3 of its periods.
void Wdt::start_sync() {
  const uint64_t hz = chip_.channel_hz(3);
  sync_until_ = chip_.now_ps() + (hz == 0 ? 0 : 3 * Chip::kPsPerSecond / hz);
}

uint32_t Wdt::read(uint32_t offset, unsigned size) {
  regs_.set(7, chip_.now_ps() < sync_until_ ? 0x80 : 0, 1);
  return regs_.get(offset, size);
}

void Wdt::write(uint32_t offset, uint32_t value, unsigned size) {
  if (touches(offset, size, 0x01, 2) && enabled()) {
    chip_.violation("write to WDT CONFIG/EWCTRL while the WDT is enabled (datasheet 18.8.2: "
                    "enable-protected)");
    return;
  }
  if (touches(offset, size, 0x08, 1)) {
    const uint32_t key = (value >> (8 * (0x08 - offset))) & 0xFF;
    // 18.6.2.2: writing any value other than 0xA5 to CLEAR resets the system immediately.
    if (key != 0xA5) {
      chip_.violation("WDT CLEAR written with " + hex32(key) + " instead of 0xA5: system reset");
      return;
    }
    cleared_at_ = chip_.now_ps();
    start_sync();
    return;
  }
  const bool was_enabled = enabled();
  regs_.set(offset, value, size);
  if (!was_enabled && enabled()) cleared_at_ = chip_.now_ps();
  start_sync();
  chip_.reschedule();
}

uint64_t Wdt::next_event_ps() const {
  if (!enabled()) return UINT64_MAX;
  const uint64_t period = period_ps();
  return period == UINT64_MAX ? UINT64_MAX : cleared_at_ + period;
}

void Wdt::advance(uint64_t now_ps) {
  if (now_ps < next_event_ps()) return;
  if (chip_.options().watchdog_resets) {
    chip_.request_reset(Pm::kCauseWatchdog);
  } else {
    chip_.violation("watchdog expired: the main loop stopped kicking it (the chip would reset; "
                    "--watchdog-resets lets it)");
  }
}

}  // namespace hmc::emu
