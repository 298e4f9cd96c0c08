// Thumb cycle table (cycles.h). Rows of DDI0484C table 3-1, as used here:
//   data processing, MOV, ADD/SUB, compare, logic, shifts, extend, reverse  1
//   MULS (the SAMD21's single-cycle multiplier option, SAMD21 datasheet 11.1.1)  1
//   ADD/MOV with PC as destination                                          2
//   LDR/STR (all sizes and addressing modes, literal included)              2
//   LDM/STM: 1 + N;  PUSH: 1 + N;  POP: 1 + N;  POP with PC: 3 + N
//   B<cond> taken 2 (not taken 1), B 2, BL 3, BX/BLX 2
//   BL, MRS, MSR, DMB, DSB, ISB 3, CPSIE/CPSID 1, NOP/hints 1, SVC/BKPT (trap)
#include "cycles.h"

namespace hmc::emu {
namespace {

unsigned popcount8(unsigned v) {
  unsigned n = 0;
  for (; v != 0; v &= v - 1) ++n;
  return n;
}

uint32_t cycles16(uint16_t op) {
  if ((op & 0xF800) == 0x4800) return 2;                      // LDR literal
  if ((op & 0xF000) == 0x5000) return 2;                      // LDR/STR register offset
  if ((op & 0xE000) == 0x6000) return 2;                      // LDR/STR(B) immediate
  if ((op & 0xF000) == 0x8000) return 2;                      // LDRH/STRH immediate
  if ((op & 0xF000) == 0x9000) return 2;                      // LDR/STR SP-relative
  if ((op & 0xF000) == 0xC000) return 1 + popcount8(op & 0xFF);  // LDM/STM
  if ((op & 0xFE00) == 0xB400) return 1 + popcount8(op & 0xFF) + ((op >> 8) & 1);  // PUSH
  if ((op & 0xFE00) == 0xBC00) {                              // POP
    return 1 + popcount8(op & 0xFF) + ((op & 0x100) != 0 ? 3 : 0);
  }
  if ((op & 0xFF00) == 0x4700) return 2;                      // BX/BLX
  if ((op & 0xFF00) == 0x4400 || (op & 0xFF00) == 0x4600) {   // ADD/MOV high registers
    return ((op & 0x80) != 0 && (op & 7) == 7) ? 2 : 1;       // PC as destination
  }
  if ((op & 0xF000) == 0xD000) return (op & 0x0F00) >= 0x0E00 ? 1 : 2;  // B<cond>; UDF/SVC
  if ((op & 0xF800) == 0xE000) return 2;                      // B
  return 1;
}

}  // namespace

ThumbBlock analyse_thumb_block(const uint8_t* bytes, uint32_t size, uint32_t address,
                               uint32_t flash_end, std::vector<uint32_t>* flash_lines) {
  ThumbBlock block;
  uint32_t fetched_line = UINT32_MAX;
  const auto touch = [&](uint32_t at) {
    if (flash_lines == nullptr || at >= flash_end) return;
    const uint32_t line = at / kFlashLineBytes;
    if (flash_lines->empty() || flash_lines->back() != line) flash_lines->push_back(line);
  };
  for (uint32_t at = 0; at + 1 < size;) {
    const uint16_t op = static_cast<uint16_t>(bytes[at] | bytes[at + 1] << 8);
    const uint32_t pc = address + at;
    if (pc / kFlashLineBytes != fetched_line) {
      fetched_line = pc / kFlashLineBytes;
      touch(pc);
    }
    ++block.instructions;
    block.ends_in_conditional_branch = false;
    if ((op & 0xE000) == 0xE000 && (op & 0x1800) != 0) {      // 32-bit instruction
      block.cycles += 3;  // BL, MRS, MSR, DMB, DSB, ISB: 3 each
      if ((pc + 2) / kFlashLineBytes != fetched_line) {
        fetched_line = (pc + 2) / kFlashLineBytes;
        touch(pc + 2);
      }
      at += 4;
      continue;
    }
    block.cycles += cycles16(op);
    if ((op & 0xF800) == 0x4800) {  // LDR literal: the word at Align(PC + 4, 4) + imm8 * 4
      touch(((pc + 4) & ~3u) + (op & 0xFFu) * 4);
      fetched_line = UINT32_MAX;    // the fetch after it reads its line again from the cache
    }
    block.ends_in_conditional_branch = (op & 0xF000) == 0xD000 && (op & 0x0F00) < 0x0E00;
    at += 2;
  }
  return block;
}

}  // namespace hmc::emu
