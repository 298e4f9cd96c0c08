// The Cortex-M0+ on Unicorn (cpu.h). Exception entry and return: ARMv6-M Architecture
// Reference Manual B1.5.6 (the 8-word frame, 8-byte stack alignment with xPSR bit 9) and
// B1.5.8 (EXC_RETURN: 0xFFFFFFF1 handler mode, 0xFFFFFFF9 thread mode on the main stack).
#include "cpu.h"

#include <cstring>

#include "../chip/hex.h"
#include "../chip/nvmctrl.h"
#include "../chip/scs.h"
#include "cycles.h"

namespace hmc::emu {
namespace {

constexpr uint32_t kFlashBase = 0x00000000, kFlashSize = 256 * 1024;
constexpr uint32_t kNvmRowsBase = 0x00800000, kNvmRowsSize = 0x8000;
constexpr uint32_t kRamBase = 0x20000000, kRamSize = 32 * 1024;
// The peripheral regions the chip dispatches (SAMD21 datasheet 9.2).
constexpr uint32_t kRegions[][2] = {{0x40000000, 0x10000}, {0x41000000, 0x10000},
                                    {0x42000000, 0x10000}, {0x60000000, 0x400},
                                    {0xE000E000, 0x1000}};
// DDI0484C 3.3: 15 cycles from an interrupt to its handler's first instruction (zero wait
// states). The return's cost is not in the manual: 13 cycles is a guess (the 8-word unstack).
constexpr uint64_t kEntryCycles = 15, kReturnCycles = 13;
constexpr uint32_t kExceptionExit = 8;  // Unicorn's interrupt number for an EXC_RETURN branch
constexpr uint32_t kBreakpoint = 7;     // ... for BKPT
constexpr uint32_t kIobusBase = 0x60000000;

const char* fault_name(uint32_t intno) {
  switch (intno) {
    case 1: return "undefined instruction";
    case 2: return "SVC with no handler modelled";
    case 3: return "instruction fetch abort";
    case 4: return "data abort";
    case 7: return "breakpoint";
    case 18: return "invalid state (a branch to an even address: ARM state)";
    case 22: return "unaligned access";
    default: return "exception";
  }
}

}  // namespace

Cpu::Cpu(Chip& chip, const ElfImage& image, const CpuOptions& options)
    : chip_(chip), image_(image), options_(options) {}

Cpu::~Cpu() {
  if (uc_ != nullptr) uc_close(uc_);
}

uint32_t Cpu::reg(int id) const {
  uint32_t value = 0;
  uc_reg_read(uc_, id, &value);
  return value;
}

void Cpu::set_reg(int id, uint32_t value) { uc_reg_write(uc_, id, &value); }

uint32_t Cpu::pc() const { return reg(UC_ARM_REG_PC); }

std::string Cpu::where(uint32_t address) const {
  const std::string line = image_.source_line(address);
  return image_.function_at(address) + " (" + hex32(address) + (line.empty() ? "" : ", " + line) + ")";
}

// RAM is the engine's memory mapped from ram_: the exception frames and the DMAC's transfers
// reach it directly. (uc_mem_write looks for translated code to invalidate on every call,
// allocating as it goes; no code runs from RAM here.)
bool Cpu::read(uint32_t address, void* bytes, uint32_t count) {
  if (address >= kRamBase && address - kRamBase + uint64_t{count} <= kRamSize) {
    std::memcpy(bytes, ram_.data() + (address - kRamBase), count);
    return true;
  }
  const bool in_flash = address + uint64_t{count} <= kFlashSize;
  return in_flash && uc_mem_read(uc_, address, bytes, count) == UC_ERR_OK;
}

bool Cpu::write(uint32_t address, const void* bytes, uint32_t count) {
  if (address >= kRamBase && address - kRamBase + uint64_t{count} <= kRamSize) {
    std::memcpy(ram_.data() + (address - kRamBase), bytes, count);
    return true;
  }
  return false;
}

bool Cpu::init(std::string& error) {
  uc_err err = uc_open(UC_ARCH_ARM, static_cast<uc_mode>(UC_MODE_THUMB | UC_MODE_MCLASS), &uc_);
  if (err != UC_ERR_OK) {
    error = std::string("cannot start the CPU engine: ") + uc_strerror(err);
    return false;
  }
  err = uc_ctl_set_cpu_model(uc_, UC_CPU_ARM_CORTEX_M0);
  const auto map = [&](uint32_t base, uint32_t size, uint32_t perms) {
    if (err == UC_ERR_OK) err = uc_mem_map(uc_, base, size, perms);
  };
  map(kFlashBase, kFlashSize, UC_PROT_READ | UC_PROT_EXEC);
  map(kNvmRowsBase, kNvmRowsSize, UC_PROT_READ);
  if (err == UC_ERR_OK) err = uc_mem_map_ptr(uc_, kRamBase, kRamSize, UC_PROT_ALL, ram_.data());
  if (err != UC_ERR_OK) {
    error = std::string("cannot map the chip's memory: ") + uc_strerror(err);
    return false;
  }
  for (const auto& region : kRegions) {
    regions_.push_back(std::make_unique<MmioRegion>(MmioRegion{this, region[0]}));
    err = uc_mmio_map(uc_, region[0], region[1], on_mmio_read, regions_.back().get(),
                      on_mmio_write, regions_.back().get());
    if (err != UC_ERR_OK) {
      error = std::string("cannot map the peripheral regions: ") + uc_strerror(err);
      return false;
    }
  }
  // The NVM's contents are NVMCTRL's (emu/chip/nvmctrl.h): the image goes into its flash, and
  // the CPU reads the flash and the NVM rows (user row, software calibration) as it holds them;
  // the rest of the rows' space reads as erased (ones).
  Nvmctrl& nvm = chip_.nvmctrl();
  for (const Segment& s : image_.segments) {
    if (s.address < kFlashBase || !nvm.load_flash(s.address, s.bytes)) {
      error = "the image has bytes at " + hex32(s.address) + ", outside the SAMD21G18's 256 KB "
              "flash: linked for another chip or address";
      return false;
    }
  }
  uc_mem_write(uc_, kFlashBase, nvm.flash().data(), kFlashSize);
  std::vector<uint8_t> rows(kNvmRowsSize, 0xFF);
  for (uint32_t base : {Nvmctrl::kUserRow, Nvmctrl::kCalibrationArea}) {
    for (uint32_t i = 0; i < Nvmctrl::kRowSize; ++i) {
      rows[base - kNvmRowsBase + i] = static_cast<uint8_t>(nvm.read_memory(base + i, 1));
    }
  }
  uc_mem_write(uc_, kNvmRowsBase, rows.data(), kNvmRowsSize);
  chip_.set_memory(this);

  // One fixed exit address (never reached: it is not in the chip's memory map), set once:
  // uc_emu_start's own `until` would invalidate translations at every start.
  uint64_t exits[] = {0xFFFFFFFEu};
  if (err == UC_ERR_OK) err = uc_ctl_exits_enable(uc_);
  if (err == UC_ERR_OK) err = uc_ctl_set_exits(uc_, exits, 1);
  if (err != UC_ERR_OK) {
    error = std::string("cannot configure the CPU engine: ") + uc_strerror(err);
    return false;
  }
  uc_hook hook;
  uc_hook_add(uc_, &hook, UC_HOOK_BLOCK, reinterpret_cast<void*>(on_block), this, 1, 0);
  hooks_.push_back(hook);
  uc_hook_add(uc_, &hook, UC_HOOK_INTR, reinterpret_cast<void*>(on_interrupt), this, 1, 0);
  hooks_.push_back(hook);
  uc_hook_add(uc_, &hook, UC_HOOK_MEM_INVALID, reinterpret_cast<void*>(on_invalid), this, 1, 0);
  hooks_.push_back(hook);
  return true;
}

bool Cpu::reset(uint32_t vector_table, std::string& error) {
  uint32_t words[2];
  if (!read(vector_table, words, 8)) {
    error = "no vector table at " + hex32(vector_table);
    return false;
  }
  const uint32_t sp = words[0], entry = words[1];
  if (sp < kRamBase || sp > kRamBase + kRamSize || (sp & 3) != 0) {
    error = "the vector table at " + hex32(vector_table) + " gives initial SP " + hex32(sp) +
            ", not in the SAMD21G18's RAM (0x20000000-0x20008000)";
    return false;
  }
  if ((entry & 1) == 0 || (entry & ~1u) >= kFlashSize || (entry & ~1u) < vector_table) {
    error = "the vector table at " + hex32(vector_table) + " gives reset handler " + hex32(entry) +
            ", not a Thumb address in the image's flash";
    return false;
  }
  active_.clear();
  thread_since_ = chip_.cycles();
  chip_.scs().reset();
  chip_.scs().set_vtor(vector_table);
  set_reg(UC_ARM_REG_IPSR, 0);
  set_reg(UC_ARM_REG_PRIMASK, 0);
  set_reg(UC_ARM_REG_CONTROL, 0);
  set_reg(UC_ARM_REG_MSP, sp);
  set_reg(UC_ARM_REG_SP, sp);
  set_reg(UC_ARM_REG_LR, 0xFFFFFFFF);
  set_reg(UC_ARM_REG_PC, entry);
  return true;
}

// Each translated block is analysed once; flash blocks by their start address in a flat
// table, RAM blocks likewise while their bytes are unchanged.
const Cpu::BlockCost& Cpu::block_cost(uint64_t address, uint32_t size) {
  BlockCost* cached = address < kFlashSize ? &flash_costs_[address / 2] : nullptr;
  if (cached != nullptr && cached->size == size) return *cached;
  // (A block ends within a 1 KiB page, so its cycles fit the table's fields.)
  if (address >= kRamBase && address - kRamBase + size <= kRamSize && size <= 1024) {
    const uint8_t* code = ram_.data() + (address - kRamBase);
    BlockCost& ram = ram_costs_[(address - kRamBase) / 2];
    if (ram.size == size && std::memcmp(code, ram_code_.data() + ram.code_at, size) == 0) {
      return ram;
    }
    if (ram_code_.size() > (1u << 22)) {
      for (BlockCost& c : ram_costs_) c = BlockCost{};
      ram_code_.clear();
    }
    const ThumbBlock block =
        analyse_thumb_block(code, size, static_cast<uint32_t>(address), kFlashSize, nullptr);
    ram = BlockCost{};
    ram.size = static_cast<uint16_t>(size);
    ram.cycles = static_cast<uint16_t>(block.cycles);
    ram.instructions = static_cast<uint16_t>(block.instructions);
    ram.code_at = static_cast<uint32_t>(ram_code_.size());
    ram.ends_in_conditional_branch = block.ends_in_conditional_branch;
    ram_code_.insert(ram_code_.end(), code, code + size);
    return ram;
  }
  if (flash_lines_.size() > (1u << 22)) {
    // Blocks re-translated with other sizes left old line lists behind: start afresh.
    for (BlockCost& c : flash_costs_) c = BlockCost{};
    flash_lines_.clear();
  }
  std::vector<uint8_t> code(size);
  std::vector<uint32_t>& lines = cached != nullptr ? flash_lines_ : scratch_lines_;
  if (cached == nullptr) lines.clear();
  const uint32_t lines_at = static_cast<uint32_t>(lines.size());
  ThumbBlock block;
  if (uc_mem_read(uc_, address, code.data(), size) == UC_ERR_OK) {
    block = analyse_thumb_block(code.data(), size, static_cast<uint32_t>(address), kFlashSize,
                                &lines);
  } else {
    block.cycles = block.instructions = size / 2;
  }
  BlockCost cost;
  cost.size = static_cast<uint16_t>(size);
  cost.cycles = static_cast<uint16_t>(block.cycles);
  cost.instructions = static_cast<uint16_t>(block.instructions);
  cost.lines = static_cast<uint16_t>(lines.size() - lines_at);
  cost.lines_at = lines_at;
  cost.ends_in_conditional_branch = block.ends_in_conditional_branch;
  // Blocks are short (the engine ends a translation block within a page); a size beyond the
  // table's fields would be analysed on each run.
  if (cached != nullptr && size <= UINT16_MAX && block.cycles <= UINT16_MAX) {
    *cached = cost;
    return *cached;
  }
  scratch_cost_ = cost;
  return scratch_cost_;
}

// Wait states of reading `lines` from flash through the NVM cache, as NVMCTRL CTRLB sets them
// (SAMD21 datasheet, NVMCTRL "Cache"; the READMODE descriptions in Microchip's register
// description): NO_MISS_PENALTY, the reset value, charges RWS on a miss and nothing on a hit;
// LOW_POWER one wait state more on a miss; DETERMINISTIC, and the cache disabled, RWS on every
// read.
uint32_t Cpu::flash_waits(const uint32_t* lines, uint32_t count) {
  uint32_t waits = 0;
  for (uint32_t i = 0; i < count; ++i) {
    uint32_t& tag = cache_tags_[lines[i] % 8];
    if (tag != lines[i]) {
      if (!nvm_.cache_off) tag = lines[i];
      waits += nvm_.miss;
    } else if (nvm_.every_read) {
      waits += nvm_.rws;
    }
  }
  return waits;
}

// NVMCTRL CTRLB's read settings, taken at each chunk's start and after a write to NVMCTRL.
void Cpu::read_nvm_settings() {
  const Nvmctrl& nvm = chip_.nvmctrl();
  nvm_.rws = nvm.read_wait_states();
  nvm_.cache_off = nvm.cache_disabled();
  nvm_.every_read = nvm_.cache_off || nvm.read_mode() == 2;
  nvm_.miss = nvm_.rws + (nvm.read_mode() == 1 ? 1 : 0);
}

void Cpu::on_block(uc_engine*, uint64_t address, uint32_t size, void* user) {
  Cpu& cpu = *static_cast<Cpu*>(user);
  Chip& chip = cpu.chip_;
  cpu.block_address_ = static_cast<uint32_t>(address);
  if (chip.reschedule_requested() && !chip.stopped()) {
    // A register write moved a peripheral's next event or the CPU clock: catch up and take the
    // new deadline without leaving the engine (no CPU state changes here).
    chip.advance();
    cpu.set_deadline();
  }
  // A stop requested here takes effect before the block runs: the block is charged only when
  // it runs.
  if (chip.stopped() || cpu.exited_ || chip.cycles() >= cpu.deadline_cycles_) {
    uc_emu_stop(cpu.uc_);
    return;
  }
  const BlockCost& cost = cpu.block_cost(address, size);
  cpu.instructions_ += cost.instructions;
  // A call enters a function at a branch target, where a block starts.
  if (address == (cpu.options_.count_calls_at & ~1u)) ++cpu.calls_;
  if (cpu.options_.cost == CostModel::kInstructions) {
    chip.charge_cycles(cost.instructions);
  } else {
    uint64_t cycles = cost.cycles;
    // DDI0484C table 3-1: a conditional branch not taken costs 1 cycle, taken 2.
    if (cpu.previous_conditional_ && address == cpu.previous_end_) cycles -= 1;
    if (cost.lines != 0) {
      const uint32_t* lines =
          (&cost == &cpu.scratch_cost_ ? cpu.scratch_lines_ : cpu.flash_lines_).data() +
          cost.lines_at;
      const uint32_t waits = cpu.flash_waits(lines, cost.lines);
      cpu.flash_wait_cycles_ += waits;
      cycles += waits;
    }
    chip.charge_cycles(cycles);
  }
  cpu.previous_end_ = address + size;
  cpu.previous_conditional_ = cost.ends_in_conditional_branch;
  if (chip.take_irq_dirty()) {
    const bool primask = (cpu.reg(UC_ARM_REG_PRIMASK) & 1) != 0;
    if (chip.scs().ready_exception(primask) != 0) {
      uc_emu_stop(cpu.uc_);
    } else if (primask && chip.scs().ready_exception(false) != 0) {
      chip.irq_changed();  // masked for now: look again at the next block (CPSIE)
    }
  }
}

uint64_t Cpu::on_mmio_read(uc_engine*, uint64_t offset, unsigned size, void* user) {
  const MmioRegion& region = *static_cast<MmioRegion*>(user);
  Cpu& cpu = *region.cpu;
  // DDI0484C, "Single-cycle I/O port": a load or store there takes one cycle, not the two the
  // block was charged.
  if (region.base == kIobusBase && cpu.options_.cost == CostModel::kCycles) cpu.chip_.refund_cycles(1);
  const uint32_t value = cpu.chip_.bus_read(region.base + static_cast<uint32_t>(offset), size);
  if (cpu.chip_.stopped()) uc_emu_stop(cpu.uc_);
  return value;
}

void Cpu::on_mmio_write(uc_engine*, uint64_t offset, unsigned size, uint64_t value, void* user) {
  const MmioRegion& region = *static_cast<MmioRegion*>(user);
  Cpu& cpu = *region.cpu;
  if (region.base == kIobusBase && cpu.options_.cost == CostModel::kCycles) cpu.chip_.refund_cycles(1);
  const uint32_t address = region.base + static_cast<uint32_t>(offset);
  cpu.chip_.bus_write(address, static_cast<uint32_t>(value), size);
  if (address - Nvmctrl::kBase < 0x100) cpu.read_nvm_settings();  // CTRLB applies at once
  if (cpu.chip_.stopped()) uc_emu_stop(cpu.uc_);
}

bool Cpu::on_invalid(uc_engine*, uc_mem_type type, uint64_t address, int size, int64_t,
                     void* user) {
  Cpu& cpu = *static_cast<Cpu*>(user);
  const char* what = "access to";
  switch (type) {
    case UC_MEM_WRITE_PROT: what = "write to read-only memory (flash is written through NVMCTRL) at"; break;
    case UC_MEM_FETCH_UNMAPPED: case UC_MEM_FETCH_PROT: what = "instruction fetch from"; break;
    case UC_MEM_READ_UNMAPPED: what = "read of unmapped"; break;
    case UC_MEM_WRITE_UNMAPPED: what = "write to unmapped"; break;
    default: break;
  }
  cpu.chip_.violation(std::string(what) + " " + hex32(static_cast<uint32_t>(address)) + " (" +
                      std::to_string(size) + " bytes)");
  return false;
}

void Cpu::on_interrupt(uc_engine*, uint32_t intno, void* user) {
  Cpu& cpu = *static_cast<Cpu*>(user);
  if (intno == kExceptionExit) {
    cpu.return_from_exception();
  } else if (intno == kBreakpoint && cpu.options_.semihosting) {
    cpu.semihost_call();
  } else if (cpu.options_.run_fault_handler) {
    cpu.enter_exception(Scs::kHardFault);
  } else {
    cpu.chip_.violation(std::string("HardFault: ") + fault_name(intno) + " (engine exception " +
                        std::to_string(intno) + ")");
  }
  uc_emu_stop(cpu.uc_);
}

// ARM semihosting (the "Semihosting for AArch32 and AArch64" specification): BKPT 0xAB with the
// operation in R0 and its argument in R1. SYS_WRITE0 (0x04) writes a NUL-terminated string;
// SYS_EXIT (0x18) ends the program, R1 = 0x20026 (ADP_Stopped_ApplicationExit) for success.
void Cpu::semihost_call() {
  const uint32_t pc = reg(UC_ARM_REG_PC) & ~1u;
  uint16_t op = 0;
  if (!read(pc, &op, 2) || op != 0xBEAB) {
    chip_.violation("breakpoint (BKPT " + hex32(op) + ") that is not a semihosting call");
    return;
  }
  const uint32_t call = reg(UC_ARM_REG_R0), arg = reg(UC_ARM_REG_R1);
  if (call == 0x04) {
    char c = 0;
    for (uint32_t at = arg; read(at, &c, 1) && c != 0; ++at) semihost_output_ += c;
  } else if (call == 0x18) {
    exited_ = true;
    exit_ok_ = arg == 0x20026;
  } else {
    chip_.violation("semihosting call " + hex32(call) + " is not modelled (SYS_WRITE0, SYS_EXIT are)");
    return;
  }
  set_reg(UC_ARM_REG_PC, (pc + 2) | 1u);
}

// B1.5.6: push R0-R3, R12, LR, the return address and xPSR on the current (main) stack,
// 8-byte aligned; LR takes EXC_RETURN, IPSR the exception number, PC the vector.
void Cpu::enter_exception(unsigned exception) {
  const uint32_t ipsr = reg(UC_ARM_REG_IPSR) & 0x3F;
  if ((reg(UC_ARM_REG_CONTROL) & 2) != 0) {
    chip_.violation("exception taken on the process stack (CONTROL.SPSEL): not modelled");
    return;
  }
  uint32_t sp = reg(UC_ARM_REG_SP);
  uint32_t xpsr = reg(UC_ARM_REG_XPSR) | (1u << 24);
  if ((sp & 4) != 0) {
    sp -= 4;
    xpsr |= 1u << 9;
  } else {
    xpsr &= ~(1u << 9);
  }
  sp -= 32;
  const uint32_t frame[8] = {reg(UC_ARM_REG_R0), reg(UC_ARM_REG_R1), reg(UC_ARM_REG_R2),
                             reg(UC_ARM_REG_R3), reg(UC_ARM_REG_R12), reg(UC_ARM_REG_LR),
                             reg(UC_ARM_REG_PC), xpsr};
  if (!write(sp, frame, sizeof frame)) {
    chip_.violation("stack overflow: exception frame at " + hex32(sp) + " is outside RAM");
    return;
  }
  uint32_t vector = 0;
  if (!read(chip_.scs().vtor() + 4 * exception, &vector, 4) || (vector & 1) == 0) {
    chip_.violation("vector " + std::to_string(exception) + " at VTOR " +
                    hex32(chip_.scs().vtor()) + " is not a Thumb address in flash: " + hex32(vector));
    return;
  }
  const uint64_t entered = chip_.cycles();
  if (active_.empty()) thread_cycles_ += entered - thread_since_;
  uint64_t entry_waits = 0;
  if (options_.cost == CostModel::kCycles) {
    // The vector is read from flash (the NVM cache and its wait states, flash_waits).
    const uint32_t line = (chip_.scs().vtor() + 4 * exception) / kFlashLineBytes;
    const uint32_t waits = flash_waits(&line, 1);
    flash_wait_cycles_ += waits;
    entry_waits = waits;
    chip_.charge_cycles(waits);
  }
  previous_conditional_ = false;
  set_reg(UC_ARM_REG_SP, sp);
  set_reg(UC_ARM_REG_LR, ipsr != 0 ? 0xFFFFFFF1u : 0xFFFFFFF9u);
  set_reg(UC_ARM_REG_IPSR, exception);
  set_reg(UC_ARM_REG_PC, vector);
  chip_.scs().acknowledge(exception);
  chip_.charge_cycles(options_.cost == CostModel::kCycles ? kEntryCycles : 0);
  active_.push_back(Active{exception, entered, instructions_, flash_wait_cycles_ - entry_waits});
}

// B1.5.8: unstack the frame from the main stack, undo the alignment word, back to the
// interrupted context.
void Cpu::return_from_exception() {
  const uint32_t exc_return = reg(UC_ARM_REG_PC) | 1u;
  if (exc_return != 0xFFFFFFF1u && exc_return != 0xFFFFFFF9u) {
    chip_.violation("EXC_RETURN " + hex32(exc_return) + ": only the main stack is modelled");
    return;
  }
  uint32_t sp = reg(UC_ARM_REG_SP);
  uint32_t frame[8];
  if (!read(sp, frame, sizeof frame)) {
    chip_.violation("exception return with the stack at " + hex32(sp) + ", outside RAM");
    return;
  }
  sp += 32;
  if ((frame[7] & (1u << 9)) != 0) sp += 4;
  chip_.charge_cycles(options_.cost == CostModel::kCycles ? kReturnCycles : 0);
  if (!active_.empty()) {
    const Active done = active_.back();
    active_.pop_back();
    account_return(done);
  }
  set_reg(UC_ARM_REG_R0, frame[0]);
  set_reg(UC_ARM_REG_R1, frame[1]);
  set_reg(UC_ARM_REG_R2, frame[2]);
  set_reg(UC_ARM_REG_R3, frame[3]);
  set_reg(UC_ARM_REG_R12, frame[4]);
  set_reg(UC_ARM_REG_LR, frame[5]);
  set_reg(UC_ARM_REG_SP, sp);
  set_reg(UC_ARM_REG_APSR, frame[7] & 0xF8000000u);
  set_reg(UC_ARM_REG_IPSR, frame[7] & 0x3F);
  set_reg(UC_ARM_REG_PC, frame[6] | 1u);  // bit 0 keeps the engine in Thumb state
}

void Cpu::set_deadline() {
  read_nvm_settings();
  const uint64_t ps = chip_.next_event_ps() < until_ps_ ? chip_.next_event_ps() : until_ps_;
  deadline_cycles_ = chip_.cycles_at(ps);
}

void Cpu::account_return(const Active& done) {
  HandlerFigures& figures = handler_figures_[done.exception];
  ++figures.count;
  figures.cycles += chip_.cycles() - done.entered_cycles;
  figures.instructions += instructions_ - done.entered_instructions;
  figures.flash_wait_cycles += flash_wait_cycles_ - done.entered_waits;
  if (active_.empty()) thread_since_ = chip_.cycles();
  chip_.scs().complete(done.exception);
}

// When the engine is stopped while an EXC_RETURN branch is in flight, it completes the return
// itself at the next start (its own M-profile unstacking) without the interrupt hook: the
// bookkeeping then follows IPSR, which names the exception still running (0: none).
void Cpu::sync_active() {
  const unsigned ipsr = reg(UC_ARM_REG_IPSR) & 0x3F;
  while (!active_.empty() && active_.back().exception != ipsr) {
    const Active done = active_.back();
    active_.pop_back();
    chip_.charge_cycles(options_.cost == CostModel::kCycles ? kReturnCycles : 0);
    account_return(done);
  }
}

void Cpu::run_until(uint64_t until_ps) {
  while (!chip_.stopped() && !exited_ && chip_.now_ps() < until_ps) {
    sync_active();
    chip_.advance();
    if (chip_.stopped()) break;
    const bool primask = (reg(UC_ARM_REG_PRIMASK) & 1) != 0;
    if (const unsigned e = chip_.scs().ready_exception(primask); e != 0) {
      enter_exception(e);
      if (chip_.stopped()) break;
    }
    until_ps_ = until_ps;
    set_deadline();
    chip_.take_irq_dirty();
    // An interrupt held back only by PRIMASK is taken as soon as CPSIE/MSR clears it (B1.5.4):
    // keep looking at every block until then. Without this a pending level (a UART byte)
    // waited for the next peripheral event, and three such waits lost a received byte.
    if (primask && chip_.scs().ready_exception(false) != 0) chip_.irq_changed();
    ++chunks_;
    const uc_err err = uc_emu_start(uc_, pc() | 1u, 0xFFFFFFFFu, 0, 0);
    if (err != UC_ERR_OK && !chip_.stopped()) {
      chip_.violation(std::string("the CPU stopped: ") + uc_strerror(err));
    }
  }
}

}  // namespace hmc::emu
