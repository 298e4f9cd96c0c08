// Cortex-M0+ cycle counts of Thumb instructions, after the ARM Cortex-M0+ Technical Reference
// Manual (DDI0484C), section 3.3 "Instruction set summary", table 3-1 (cycle counts with zero
// wait-state memory). A translated block is analysed once: the sum of its instructions' cycles
// with the block's last branch counted as taken (the CPU takes one cycle back when a block
// ending in a conditional branch falls through), its instruction count, and the flash lines its
// instruction fetches and literal loads touch in order (for the NVM cache, cpu.h).
#pragma once

#include <cstdint>
#include <vector>

namespace hmc::emu {

struct ThumbBlock {
  uint32_t cycles = 0;
  uint32_t instructions = 0;
  bool ends_in_conditional_branch = false;
};

// The NVM cache's line size (SAMD21 datasheet, NVMCTRL "Cache": 8 lines of 64 bits).
constexpr uint32_t kFlashLineBytes = 8;

// Analyses the Thumb instructions in bytes[0, size) found at `address`: 16-bit instructions and
// the 32-bit BL, MRS, MSR, DMB/DSB/ISB. Appends to `flash_lines` (when not null) the line number
// (address / kFlashLineBytes) of each flash line below `flash_end` the block reads, in the order
// the CPU reads them: a fetch entering a new line, then a literal load's line.
ThumbBlock analyse_thumb_block(const uint8_t* bytes, uint32_t size, uint32_t address,
                               uint32_t flash_end, std::vector<uint32_t>* flash_lines);

}  // namespace hmc::emu
