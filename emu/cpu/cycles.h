// Cortex-M0+ cycle counts of Thumb instructions, after the ARM Cortex-M0+ Technical Reference
// Manual (DDI0484C), section 3.3 "Instruction set summary", table 3-1 (cycle counts with zero
// wait-state memory). A translated block is costed once: the sum of its instructions, with the
// block's last branch counted as taken.
#pragma once

#include <cstdint>

namespace hmc::emu {

// Cycles of the Thumb instructions in bytes[0, size): 16-bit instructions and the 32-bit BL,
// MRS, MSR, DMB/DSB/ISB.
uint32_t thumb_block_cycles(const uint8_t* bytes, uint32_t size);

}  // namespace hmc::emu
