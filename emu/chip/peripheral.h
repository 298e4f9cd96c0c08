// One memory-mapped block of the emulated SAMD21: the bus hands it every access that falls in
// its address range, as an offset from the block's base. Reads and writes are the size the CPU
// made them (1, 2 or 4 bytes); a block that refuses an access (a masked bus clock, a write to
// an enable-protected field) reports it through the chip's violation log, not by throwing.
#pragma once

#include <cstdint>

namespace hmc::emu {

class Peripheral {
public:
  virtual ~Peripheral() = default;
  virtual uint32_t read(uint32_t offset, unsigned size) = 0;
  virtual void write(uint32_t offset, uint32_t value, unsigned size) = 0;
};

}  // namespace hmc::emu
