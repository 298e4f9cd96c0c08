// The chip (chip.h): block construction, the memory map of the peripheral regions (SAMD21
// datasheet 9.2, "Product Mapping"), the PM bus-clock masks that gate each block (16.8.8-10),
// the interrupt line numbers (11.2.2, Table 11-3), and virtual time.
#include "chip.h"


#include "../board/board.h"
#include "dmac.h"
#include "hex.h"
#include "nvmctrl.h"
#include "port.h"
#include "scs.h"
#include "sercom.h"
#include "system.h"
#include "timers.h"

namespace hmc::emu {
namespace {

// The regions the bus dispatches, in 1 KB pages.
struct Region {
  uint32_t base, size;
};
constexpr Region kRegions[] = {{0x40000000, 0x10000}, {0x41000000, 0x10000},
                               {0x42000000, 0x10000}, {0x60000000, 0x400},
                               {0xE000E000, 0x1000}};

}  // namespace

Chip::Chip(const ChipOptions& options) : options_(options) {
  pm_ = std::make_unique<Pm>(*this);
  sysctrl_ = std::make_unique<Sysctrl>(*this);
  gclk_ = std::make_unique<Gclk>(*this);
  nvmctrl_ = std::make_unique<Nvmctrl>([this](const std::string& message) { violation(message); });
  wdt_ = std::make_unique<Wdt>(*this);
  scs_ = std::make_unique<Scs>(*this);
  port_ = std::make_unique<Port>(*this);
  eic_ = std::make_unique<Eic>(*this);
  for (unsigned n = 0; n < 6; ++n) sercoms_[n] = std::make_unique<Sercom>(*this, n);
  // DMAC trigger sources (20.8.17 CHCTRLB.TRIGSRC): TC3 OVF 0x18, MC0 0x19, MC1 0x1A; TC4 OVF
  // 0x1B, MC0 0x1C, MC1 0x1D (the table goes on with TC5 0x1E-0x20 ... TC7 MC0/MC1 0x25/0x26).
  tc3_ = std::make_unique<Tc>(*this, "TC3", 0x1B, 0x18);
  tc4_ = std::make_unique<Tc>(*this, "TC4", 0x1C, 0x1B);
  // TCC0-2 (Table 31-1 "TCC Configuration Summary": counter size, compare channels, waveform
  // outputs): GCLK channels 0x1A TCC0_TCC1 and 0x1B TCC2_TC3 (15.8.3 CLKCTRL.ID); DMAC triggers
  // TCC0 OVF 0x0D, MC0-3 0x0E-0x11; TCC1 OVF 0x12, MC0/MC1 0x13/0x14; TCC2 OVF 0x15, MC0/MC1
  // 0x16/0x17 (20.8.17 CHCTRLB.TRIGSRC).
  tccs_[0] = std::make_unique<Tcc>(*this, 0, 24, 4, 8, 0x1A, 0x0D);
  tccs_[1] = std::make_unique<Tcc>(*this, 1, 24, 2, 4, 0x1A, 0x12);
  tccs_[2] = std::make_unique<Tcc>(*this, 2, 16, 2, 2, 0x1B, 0x15);
  dma_timers_ = {tc3_.get(), tc4_.get(), tccs_[0].get(), tccs_[1].get(), tccs_[2].get()};
  dmac_ = std::make_unique<Dmac>(*this);
  board_ = std::make_unique<Board>(*this);
  hz_ = gclk_->generator_hz(0);

  size_t pages = 0;
  for (const Region& r : kRegions) pages += r.size / 0x400;
  slot_by_page_.assign(pages, -1);

  attach(0x40000400, 0x400, pm_.get(), "PM", Pm::kApbAMask, 1u << 1);
  attach(0x40000800, 0x400, sysctrl_.get(), "SYSCTRL", Pm::kApbAMask, 1u << 2);
  attach(0x40000C00, 0x400, gclk_.get(), "GCLK", Pm::kApbAMask, 1u << 3);
  attach(0x40001000, 0x400, wdt_.get(), "WDT", Pm::kApbAMask, 1u << 4);
  attach(0x40001800, 0x400, eic_.get(), "EIC", Pm::kApbAMask, 1u << 6);
  attach(0x41004000, 0x400, nvmctrl_.get(), "NVMCTRL", Pm::kApbBMask, 1u << 2);
  attach(0x41004400, 0x400, port_.get(), "PORT", Pm::kApbBMask, 1u << 3);
  attach(0x41004800, 0x400, dmac_.get(), "DMAC", Pm::kApbBMask, 1u << 4);
  for (unsigned n = 0; n < 6; ++n) {
    attach(0x42000800 + 0x400 * n, 0x400, sercoms_[n].get(), "SERCOM" + std::to_string(n),
           Pm::kApbCMask, 1u << (2 + n));
  }
  for (unsigned n = 0; n < 3; ++n) {
    attach(0x42002000 + 0x400 * n, 0x400, tccs_[n].get(), "TCC" + std::to_string(n),
           Pm::kApbCMask, 1u << (8 + n));
  }
  attach(0x42002C00, 0x400, tc3_.get(), "TC3", Pm::kApbCMask, 1u << 11);
  attach(0x42003000, 0x400, tc4_.get(), "TC4", Pm::kApbCMask, 1u << 12);
  attach(0x60000000, 0x400, &port_->iobus(), "PORT (IOBUS)", -1, 0);
  attach(0xE000E000, 0x1000, scs_.get(), "System Control Space", -1, 0);

  timed_ = {sysctrl_.get(), wdt_.get(), scs_.get()};
  timed_.insert(timed_.end(), dma_timers_.begin(), dma_timers_.end());
  for (auto& s : sercoms_) timed_.push_back(s.get());
  timed_.push_back(dmac_.get());
  timed_.push_back(board_.get());  // its devices' own deadlines (a strip's latch, a servo let go)

  for (auto& line : lines_) line = [] { return false; };
  lines_[4] = [this] { return eic_->irq(); };
  lines_[6] = [this] { return dmac_->irq(); };
  for (unsigned n = 0; n < 6; ++n) lines_[9 + n] = [this, n] { return sercoms_[n]->irq(); };
  for (unsigned n = 0; n < 3; ++n) lines_[15 + n] = [this, n] { return tccs_[n]->irq(); };
  lines_[18] = [this] { return tc3_->irq(); };
  lines_[19] = [this] { return tc4_->irq(); };
  // The 32-bit pair's interrupt comes from TC4 (the master, 30.6.2.4); TC5 is not a block of
  // its own here: an access to it is an error.
}

Chip::~Chip() = default;

void Chip::attach(uint32_t base, uint32_t size, Peripheral* block, const std::string& name,
                  int mask_register, uint32_t mask_bit) {
  slots_.push_back(Slot{block, name, base, mask_register, mask_bit});
  size_t page = 0;
  for (const Region& r : kRegions) {
    if (base >= r.base && base < r.base + r.size) {
      for (uint32_t a = base; a < base + size; a += 0x400) {
        slot_by_page_[page + (a - r.base) / 0x400] = static_cast<int>(slots_.size() - 1);
      }
      return;
    }
    page += r.size / 0x400;
  }
}

const Chip::Slot* Chip::slot_for(uint32_t address) const {
  size_t page = 0;
  for (const Region& r : kRegions) {
    if (address >= r.base && address < r.base + r.size) {
      const int index = slot_by_page_[page + (address - r.base) / 0x400];
      return index < 0 ? nullptr : &slots_[static_cast<size_t>(index)];
    }
    page += r.size / 0x400;
  }
  return nullptr;
}

void Chip::dispatch_error(uint32_t address, unsigned size, bool write) {
  violation(std::string(write ? "write to " : "read of ") + hex32(address) + " (" +
            std::to_string(size) + " bytes): no modelled block there");
}

uint32_t Chip::bus_read(uint32_t address, unsigned size) {
  const Slot* slot = slot_for(address);
  if (slot == nullptr) {
    dispatch_error(address, size, false);
    return 0;
  }
  if (address % size != 0) {
    violation("unaligned " + std::to_string(size) + "-byte read of " + slot->name + " at " +
              hex32(address) + " (ARMv6-M A3.2: unaligned accesses fault)");
    return 0;
  }
  if (slot->mask_register >= 0 && !pm_->clocked(slot->mask_register, slot->mask_bit)) {
    violation("read of " + slot->name + " at " + hex32(address) +
              " while its bus clock is masked in PM (datasheet 16.6.2.6)");
    return 0;
  }
  return slot->block->read(address - slot->base, size);
}

void Chip::bus_write(uint32_t address, uint32_t value, unsigned size) {
  const Slot* slot = slot_for(address);
  if (slot == nullptr) {
    dispatch_error(address, size, true);
    return;
  }
  if (address % size != 0) {
    violation("unaligned " + std::to_string(size) + "-byte write of " + slot->name + " at " +
              hex32(address) + " (ARMv6-M A3.2: unaligned accesses fault)");
    return;
  }
  if (slot->mask_register >= 0 && !pm_->clocked(slot->mask_register, slot->mask_bit)) {
    violation("write to " + slot->name + " at " + hex32(address) +
              " while its bus clock is masked in PM (datasheet 16.6.2.6)");
    return;
  }
  slot->block->write(address - slot->base, value, size);
}

bool Chip::irq_line(unsigned line) const { return line < kIrqLines && lines_[line](); }

void Chip::eic_line(unsigned extint, bool level) { eic_->line_changed(extint, level); }

void Chip::dma_trigger(unsigned sercom) { dmac_->sercom_ready(sercom); }

void Chip::before_port_write() {
  for (DmaTimer* timer : dma_timers_) timer->advance(access_ps());
}

bool Chip::peripheral_output(samd21::port_functions::Unit unit, unsigned instance, unsigned index) {
  using samd21::port_functions::Unit;
  if (unit == Unit::kTcc && instance < 3) return tccs_[instance]->output(index);
  if (unit == Unit::kSercom && instance < 6) return sercoms_[instance]->pad_output(index);
  return false;  // TC WO levels are not followed edge by edge (the buzzer is heard by its frequency)
}

void Chip::violation(const std::string& message) {
  if (violation_.empty()) violation_ = message;
}

void Chip::request_reset(uint8_t rcause_bit) {
  reset_requested_ = true;
  pm_->set_reset_cause(rcause_bit);
}

uint64_t Chip::generator_hz(unsigned generator) const { return gclk_->generator_hz(generator); }
uint64_t Chip::channel_hz(unsigned id) const { return gclk_->channel_hz(id); }

// The CPU runs on generator 0 divided by PM CPUSEL (16.8.3: divide by 2^CPUDIV).
void Chip::update_cpu_clock() {
  const uint64_t hz = gclk_->generator_hz(0) >> (pm_->read(0x08, 1) & 7);
  if (hz == hz_) return;
  base_ps_ = now_ps();
  base_cycles_ = cycles_;
  hz_ = hz;
}

uint64_t Chip::cycles_at(uint64_t ps) const {
  if (hz_ == 0 || ps == UINT64_MAX) return UINT64_MAX;
  if (ps <= base_ps_) return base_cycles_;
  const Wide cycles = (static_cast<Wide>(ps - base_ps_) * hz_ + kPsPerSecond - 1) / kPsPerSecond;
  return cycles > UINT64_MAX - base_cycles_ ? UINT64_MAX : base_cycles_ + static_cast<uint64_t>(cycles);
}

void Chip::charge_stall(uint64_t clock_cycles, uint64_t hz) {
  const uint64_t cpu = cpu_hz();
  // A DMAC access (master_ps_ set) waits on its own bus port, not the CPU's.
  if (hz == 0 || cpu == 0 || master_ps_ != UINT64_MAX) return;
  charge_cycles((clock_cycles * cpu + hz - 1) / hz);
}

void Chip::advance() {
  update_cpu_clock();
  const uint64_t now = now_ps();
  for (Timed* t : timed_) t->advance(now);
  uint64_t next = UINT64_MAX;
  for (const Timed* t : timed_) {
    const uint64_t e = t->next_event_ps();
    next = e < next ? e : next;
  }
  next_event_ps_ = next;
  reschedule_ = false;
}

}  // namespace hmc::emu
