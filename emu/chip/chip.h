// The emulated SAMD21G18: its clock tree and virtual time, the peripheral bus (which block an
// address falls in, the PM bus-clock masks), the interrupt lines, and the violation log that
// stops the emulator. The CPU (emu/cpu) runs the instructions; this is everything it talks to.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "../../firmware/targets/samd21/port_functions.h"
#include "peripheral.h"

namespace hmc::emu {

__extension__ typedef unsigned __int128 Wide;  // GCC/Clang: products of two 64-bit values
// a·b/c, rounded down, without overflow of the product.
inline uint64_t mul_div(uint64_t a, uint64_t b, uint64_t c) {
  return static_cast<uint64_t>(static_cast<Wide>(a) * b / c);
}

class Pm;
class Sysctrl;
class Gclk;
class Wdt;
class Scs;
class Port;
class Eic;
class Sercom;
class Tc;
class Tcc;
class Dmac;
class Nvmctrl;
class Board;

// Reads and writes of the chip's memory for bus masters other than the CPU (the DMAC).
class Memory {
 public:
  virtual ~Memory() = default;
  virtual bool read(uint32_t address, void* bytes, uint32_t count) = 0;
  virtual bool write(uint32_t address, const void* bytes, uint32_t count) = 0;
};

struct ChipOptions {
  bool crystal = true;          // a 32.768 kHz crystal on PA00/PA01
  bool after_bootloader = true; // start in the state the bootloader leaves (DFLL48M running)
  uint32_t wire_baud = 115200;  // the host side of the command UART
  bool watchdog_resets = false; // false: a watchdog expiry stops the emulator as an error
};

// A block with time-driven behaviour: the chip asks it for its next event and lets it catch up.
class Timed {
 public:
  virtual ~Timed() = default;
  virtual void advance(uint64_t now_ps) = 0;
  virtual uint64_t next_event_ps() const = 0;  // UINT64_MAX: none
};

// A timer whose compare matches are DMAC triggers: MCx is its OVF trigger + 1 + x (datasheet
// 20.8.17, CHCTRLB.TRIGSRC). A match a DMAC channel listens to is an event of the timer's, served
// at its exact time.
class DmaTimer : public Timed {
 public:
  virtual unsigned dma_trigger_base() const = 0;  // the OVF trigger
  virtual unsigned compare_channels() const = 0;
  // Bit x set: a DMAC channel is on MCx.
  virtual void set_dma_watch(unsigned channels) = 0;
};

class Chip {
 public:
  static constexpr uint64_t kPsPerSecond = 1000000000000ull;
  static constexpr unsigned kIrqLines = 28;

  explicit Chip(const ChipOptions& options);
  ~Chip();

  const ChipOptions& options() const { return options_; }
  void set_memory(Memory* memory) { memory_ = memory; }
  Memory& memory() { return *memory_; }

  // ---- Time. CPU cycles are charged by the CPU; everything else runs on picoseconds.
  // Virtual time is kept as CPU cycles since a base point; a change of the CPU clock moves the
  // base, so charging cycles costs an addition and reading the time one division.
  uint64_t now_ps() const {
    return hz_ == 0 ? base_ps_ : base_ps_ + mul_div(cycles_ - base_cycles_, kPsPerSecond, hz_);
  }
  // The time of the bus access being served: now for the CPU's; for the DMAC's, the time its
  // beat lands (set around the access: a beat served late, at the CPU's next block boundary,
  // keeps its own time in the pin trace and the STEP pulse figures).
  uint64_t access_ps() const { return master_ps_ != UINT64_MAX ? master_ps_ : now_ps(); }
  void set_master_ps(uint64_t ps) { master_ps_ = ps; }
  uint64_t master_ps() const { return master_ps_; }
  uint64_t cycles() const { return cycles_; }
  void charge_cycles(uint64_t cycles) { cycles_ += cycles; }
  // Cycles charged ahead (a block is charged before it runs) that an access turned out not to
  // take; never more than was charged since the last advance.
  void refund_cycles(uint64_t cycles) { cycles_ -= cycles; }
  // The cycle count at which virtual time reaches `ps` (at the current CPU clock).
  uint64_t cycles_at(uint64_t ps) const;
  // A bus stall measured in cycles of `hz` (a synchronisation delay), charged to the CPU.
  void charge_stall(uint64_t clock_cycles, uint64_t hz);
  uint64_t cpu_hz() const { return hz_; }
  // The frequency of the generic clock channel `id` (GCLK CLKCTRL.ID), 0 when disabled.
  uint64_t channel_hz(unsigned id) const;
  uint64_t generator_hz(unsigned generator) const;
  // Earliest time any block wants to be advanced; the CPU stops its chunk there.
  uint64_t next_event_ps() const { return next_event_ps_; }
  // Brings every timed block up to now and recomputes the next event.
  void advance();
  void reschedule() { reschedule_ = true; }
  bool reschedule_requested() const { return reschedule_; }

  // ---- Bus. Dispatches an access in one of the peripheral regions.
  uint32_t bus_read(uint32_t address, unsigned size);
  void bus_write(uint32_t address, uint32_t value, unsigned size);

  // ---- Interrupts: level of each peripheral line, as its block drives it.
  bool irq_line(unsigned line) const;
  // A pin on EIC function A changed level.
  void eic_line(unsigned extint, bool level);

  // ---- Violations and stop requests. The first one wins; the CPU stops at once.
  void violation(const std::string& message);
  const std::string& violation_message() const { return violation_; }
  bool stopped() const { return !violation_.empty() || reset_requested_; }
  // A chip reset (AIRCR.SYSRESETREQ, watchdog), with the cause for PM RCAUSE.
  void request_reset(uint8_t rcause_bit);
  bool reset_requested() const { return reset_requested_; }
  void clear_reset_request() { reset_requested_ = false; }
  // Something that may change which interrupt is pending happened.
  void irq_changed() { irq_dirty_ = true; }
  bool take_irq_dirty() {
    const bool dirty = irq_dirty_;
    irq_dirty_ = false;
    return dirty;
  }
  // The address of the access being served (for messages) is set by the CPU.
  void set_pc_hint(uint32_t pc) { pc_hint_ = pc; }

  // ---- Blocks.
  Pm& pm() { return *pm_; }
  Sysctrl& sysctrl() { return *sysctrl_; }
  Gclk& gclk() { return *gclk_; }
  const Gclk& gclk() const { return *gclk_; }
  const Sysctrl& sysctrl() const { return *sysctrl_; }
  Scs& scs() { return *scs_; }
  Port& port() { return *port_; }
  Nvmctrl& nvmctrl() { return *nvmctrl_; }
  Sercom& sercom(unsigned n) { return *sercoms_[n]; }
  Tc& tc3() { return *tc3_; }
  Tc& tc4() { return *tc4_; }
  Dmac& dmac() { return *dmac_; }
  // SERCOM `sercom`'s transmit buffer emptied at a byte's end: the DMAC may feed it (dmac.h).
  void dma_trigger(unsigned sercom);
  // A PORT register is about to be written: DMA beats the timers triggered before the access's
  // time land first, so the CPU's write and the DMAC's keep their order.
  void before_port_write();
  Tcc& tcc(unsigned n) { return *tccs_[n]; }
  // The timers whose compare matches the DMAC can be triggered by.
  const std::array<DmaTimer*, 5>& dma_timers() { return dma_timers_; }
  // The level a peripheral drives on its output signal (`unit` a port_functions::Unit: SERCOM
  // pad, TC or TCC WO[index]) now; false for a signal nothing drives.
  bool peripheral_output(samd21::port_functions::Unit unit, unsigned instance, unsigned index);
  Board& board() { return *board_; }

 private:
  struct Slot {
    Peripheral* block = nullptr;
    std::string name;
    uint32_t base = 0;
    int mask_register = -1;  // PM APBAMASK/APBBMASK/APBCMASK offset, -1: always clocked
    uint32_t mask_bit = 0;
  };
  void attach(uint32_t base, uint32_t size, Peripheral* block, const std::string& name,
              int mask_register, uint32_t mask_bit);
  const Slot* slot_for(uint32_t address) const;
  void dispatch_error(uint32_t address, unsigned size, bool write);

  ChipOptions options_;
  Memory* memory_ = nullptr;
  uint64_t base_ps_ = 0;
  uint64_t base_cycles_ = 0;
  uint64_t hz_ = 0;
  uint64_t cycles_ = 0;
  uint64_t master_ps_ = UINT64_MAX;
  void update_cpu_clock();
  uint64_t next_event_ps_ = 0;
  bool reschedule_ = true;
  bool irq_dirty_ = true;
  bool reset_requested_ = false;
  std::string violation_;
  uint32_t pc_hint_ = 0;

  std::unique_ptr<Pm> pm_;
  std::unique_ptr<Sysctrl> sysctrl_;
  std::unique_ptr<Gclk> gclk_;
  std::unique_ptr<Nvmctrl> nvmctrl_;
  std::unique_ptr<Wdt> wdt_;
  std::unique_ptr<Scs> scs_;
  std::unique_ptr<Port> port_;
  std::unique_ptr<Eic> eic_;
  std::array<std::unique_ptr<Sercom>, 6> sercoms_;
  std::unique_ptr<Tc> tc3_;
  std::unique_ptr<Tc> tc4_;
  std::array<std::unique_ptr<Tcc>, 3> tccs_;
  std::array<DmaTimer*, 5> dma_timers_{};
  std::unique_ptr<Dmac> dmac_;
  std::unique_ptr<Board> board_;
  std::vector<Slot> slots_;
  std::vector<int> slot_by_page_;  // 1 KB pages of the regions, index into slots_ or -1
  std::vector<Timed*> timed_;
  // Interrupt line → the block driving it.
  std::array<std::function<bool()>, kIrqLines> lines_;

  friend class Scs;
};

// Little-endian register storage a block keeps its plain registers in (at most 128 bytes: no
// allocation, as blocks build one per access to assemble their registers).
class RegisterBytes {
 public:
  static constexpr size_t kMax = 0x80;
  explicit RegisterBytes(size_t size) : size_(size < kMax ? size : kMax) {}
  uint32_t get(uint32_t offset, unsigned size) const {
    uint32_t value = 0;
    for (unsigned i = 0; i < size && offset + i < size_; ++i) {
      value |= uint32_t{bytes_[offset + i]} << (8 * i);
    }
    return value;
  }
  void set(uint32_t offset, uint32_t value, unsigned size) {
    for (unsigned i = 0; i < size && offset + i < size_; ++i) {
      bytes_[offset + i] = static_cast<uint8_t>(value >> (8 * i));
    }
  }
  template <typename Table>
  void load(const Table& table) {
    for (const auto& row : table) set(row.offset, row.value, row.bytes);
  }

 private:
  size_t size_;
  std::array<uint8_t, kMax> bytes_{};
};

// Does an access [offset, offset+size) touch the register [reg, reg+reg_size)?
inline bool touches(uint32_t offset, unsigned size, uint32_t reg, unsigned reg_size) {
  return offset < reg + reg_size && reg < offset + size;
}

}  // namespace hmc::emu
