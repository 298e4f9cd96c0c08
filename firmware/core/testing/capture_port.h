// CapturePort: a hal::SerialPort for host tests that receives nothing and keeps every byte the
// firmware writes, so a test can compare the board's output with the frames it expects.
#pragma once

#include <stdint.h>

#include <string>

#include "core/hal.h"

namespace hmc::testing {

class CapturePort : public hal::SerialPort {
 public:
  int read_byte() override { return -1; }
  void write(const uint8_t* bytes, uint32_t count) override {
    text.append(reinterpret_cast<const char*>(bytes), count);
  }
  std::string text;
};

}  // namespace hmc::testing
