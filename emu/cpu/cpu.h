// The Cortex-M0+ core on the Unicorn engine (Cortex-M0 model, Thumb-only ARMv6-M): flash, RAM
// and the NVM rows as memory, the peripheral regions dispatched to the chip, and the exception
// model Unicorn 2.0.1 lacks: the emulator checks for a ready exception between chunks of
// instructions (a chunk ends at the next peripheral event or when an access may have changed
// an interrupt), pushes the frame and enters the handler itself, and unstacks on the
// EXC_RETURN branch, which Unicorn reports as interrupt 8. Tail-chaining and late arrival are
// not modelled: each return unstacks fully, and a pending exception is taken after it.
#pragma once

#include <unicorn/unicorn.h>

#include <cstdint>
#include <map>
#include <memory>
#include <vector>
#include <string>

#include "../chip/chip.h"
#include "../elf/elf_image.h"

namespace hmc::emu {

// What virtual time counts. kCycles: the Cortex-M0+ cycle model (cycles.h; the flash wait
// states through the NVM cache; exception entry and return; the chip's synchronisation stalls).
// kInstructions: one cycle per instruction, as qemu's -icount counts (the calibration against
// bench/qemu, hmc-emu-bench).
enum class CostModel { kCycles, kInstructions };

struct CpuOptions {
  bool run_fault_handler = false;  // false: a HardFault stops the emulator as an error
  CostModel cost = CostModel::kCycles;
  // BKPT 0xAB is an ARM semihosting call (SYS_WRITE0, SYS_EXIT; the rest stop the emulator) and
  // not a breakpoint: bare-metal programs such as bench/qemu's print and exit this way.
  bool semihosting = false;
  // Counts the blocks that start at this address (a function's entry: its calls; a call is a
  // branch, and a block starts at every branch target); 0: none.
  uint32_t count_calls_at = 0;
};

class Cpu : public Memory {
 public:
  Cpu(Chip& chip, const ElfImage& image, const CpuOptions& options);
  ~Cpu() override;
  Cpu(const Cpu&) = delete;
  Cpu& operator=(const Cpu&) = delete;

  // Maps memory, loads the image, installs the hooks. False with `error` on failure.
  bool init(std::string& error);
  // Reset: SP and PC from the vector table at `vector_table` (ARMv6-M B1.5.5).
  bool reset(uint32_t vector_table, std::string& error);
  // Runs until virtual time reaches `until_ps` or the chip stops (a violation, a reset).
  void run_until(uint64_t until_ps);

  uint32_t pc() const;
  // "function+0x12 (0x000021A4)".
  std::string where(uint32_t address) const;

  // Cycles spent in each exception's handler, entry and return included.
  struct HandlerFigures {
    uint64_t count = 0;
    uint64_t cycles = 0;
    uint64_t instructions = 0;
    uint64_t flash_wait_cycles = 0;  // of `cycles`
  };
  const std::map<unsigned, HandlerFigures>& handler_figures() const { return handler_figures_; }

  // Cycles spent outside every exception handler (thread mode: the main loop), and the calls
  // counted at CpuOptions::count_calls_at.
  uint64_t thread_cycles() const {
    return thread_cycles_ + (active_.empty() ? chip_.cycles() - thread_since_ : 0);
  }
  uint64_t calls() const { return calls_; }

  // How many times the engine was started (each chunk of instructions).
  uint64_t chunks() const { return chunks_; }
  uint64_t instructions() const { return instructions_; }
  // Cycles the flash wait states added (NVM cache misses).
  uint64_t flash_wait_cycles() const { return flash_wait_cycles_; }

  // Semihosting: what the program wrote (taken), and its exit status once it called SYS_EXIT.
  std::string take_semihost_output() { return std::move(semihost_output_); }
  bool exited() const { return exited_; }
  bool exit_ok() const { return exit_ok_; }

  bool read(uint32_t address, void* bytes, uint32_t count) override;
  bool write(uint32_t address, const void* bytes, uint32_t count) override;

 private:
  static void on_block(uc_engine* uc, uint64_t address, uint32_t size, void* user);
  static void on_interrupt(uc_engine* uc, uint32_t intno, void* user);
  static bool on_invalid(uc_engine* uc, uc_mem_type type, uint64_t address, int size,
                         int64_t value, void* user);
  static uint64_t on_mmio_read(uc_engine* uc, uint64_t offset, unsigned size, void* user);
  static void on_mmio_write(uc_engine* uc, uint64_t offset, unsigned size, uint64_t value,
                            void* user);

  void enter_exception(unsigned exception);
  void return_from_exception();
  void sync_active();
  uint32_t reg(int id) const;
  void set_reg(int id, uint32_t value);
  struct BlockCost {
    uint16_t size = 0;  // 0: not analysed yet
    uint16_t cycles = 0;
    uint16_t instructions = 0;
    uint16_t lines = 0;       // flash lines read, in flash_lines_ from lines_at
    uint32_t lines_at = 0;
    uint32_t code_at = 0;     // RAM blocks: the bytes analysed, in ram_code_ from code_at
    bool ends_in_conditional_branch = false;
  };
  const BlockCost& block_cost(uint64_t address, uint32_t size);
  uint32_t flash_waits(const uint32_t* lines, uint32_t count);
  void read_nvm_settings();
  void semihost_call();

  Chip& chip_;
  const ElfImage& image_;
  CpuOptions options_;
  uc_engine* uc_ = nullptr;
  void set_deadline();
  uint64_t deadline_cycles_ = 0;  // the chunk ends at this cycle count
  uint64_t until_ps_ = 0;
  uint64_t chunks_ = 0;
  uint32_t block_address_ = 0;
  uint64_t instructions_ = 0;
  uint64_t flash_wait_cycles_ = 0;
  // The block before: where it ended and whether its last instruction was a conditional
  // branch (charged as taken; one cycle back when the next block starts where it ended).
  uint64_t previous_end_ = 0;
  bool previous_conditional_ = false;
  // Flash blocks by start address (halfword index); other blocks are analysed on each run.
  std::vector<BlockCost> flash_costs_ = std::vector<BlockCost>(256 * 1024 / 2);
  std::vector<uint32_t> flash_lines_;  // the flash blocks' line lists, back to back
  // RAM blocks (the step interrupt runs from RAM) likewise, kept while their bytes are the ones
  // analysed: RAM can be rewritten under the same address.
  std::vector<BlockCost> ram_costs_ = std::vector<BlockCost>(32 * 1024 / 2);
  std::vector<uint8_t> ram_code_;  // the RAM blocks' bytes, back to back
  BlockCost scratch_cost_;
  std::vector<uint32_t> scratch_lines_;
  // The NVM cache: direct-mapped, 8 lines of 64 bits (SAMD21 datasheet, NVMCTRL "Cache"); the
  // line number held by each entry, UINT32_MAX: empty.
  uint32_t cache_tags_[8] = {UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX,
                             UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX};
  struct NvmReadSettings {
    uint32_t rws = 0;          // CTRLB.RWS
    uint32_t miss = 0;         // wait states of a cache miss
    bool every_read = false;   // DETERMINISTIC or the cache disabled: RWS on every read
    bool cache_off = false;    // CTRLB.CACHEDIS
  } nvm_;
  std::vector<uint8_t> ram_ = std::vector<uint8_t>(32 * 1024);
  std::string semihost_output_;
  bool exited_ = false;
  bool exit_ok_ = false;
  struct Active {
    unsigned exception;
    uint64_t entered_cycles;
    uint64_t entered_instructions;
    uint64_t entered_waits;
  };
  void account_return(const Active& done);
  std::vector<Active> active_;
  uint64_t thread_cycles_ = 0;  // thread mode's cycles up to thread_since_
  uint64_t thread_since_ = 0;   // when thread mode was last entered
  uint64_t calls_ = 0;
  std::map<unsigned, HandlerFigures> handler_figures_;
  std::vector<uc_hook> hooks_;
  struct MmioRegion {
    Cpu* cpu;
    uint32_t base;
  };
  std::vector<std::unique_ptr<MmioRegion>> regions_;
};

}  // namespace hmc::emu
