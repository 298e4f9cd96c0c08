// GPIO and pin multiplexing for the SAMD21 port: configure a board::Pin as an output, an input
// with a pull, or a peripheral function, and set or read it. Setting and reading go through the
// IOBUS alias of PORT (single cycle), so they are cheap enough for the step interrupt.
#pragma once

#include <stdint.h>

#include "board.h"
#include "reg_access.h"
#include "regs_port.h"

namespace hmc::samd21 {

// Output, driven to `high` before the direction switches (no glitch).
void pin_output(board::Pin pin, bool high);
// Input with the pull-up (`pull_up`) or no pull.
void pin_input(board::Pin pin, bool pull_up);
// Hands the pin to a peripheral; input and pull settings are kept.
void pin_function(board::Pin pin, port::Function function);
// Turns the input buffer on, so pin_read() sees the pin even while an output or a peripheral
// drives it.
void pin_sense(board::Pin pin);
// Takes the pin back from its peripheral: it is a plain GPIO again (as last configured).
void pin_release(board::Pin pin);

inline uint32_t pin_mask(board::Pin pin) { return 1u << pin.number; }
inline uint32_t pin_group_iobus(board::Pin pin) {
  return port::kIobusBase + port::kGroupStride * pin.group;
}

inline void pin_set(board::Pin pin, bool high) {
  r32(pin_group_iobus(pin) + (high ? port::kOutSet : port::kOutClr)) = pin_mask(pin);
}
inline bool pin_read(board::Pin pin) {
  return (r32(pin_group_iobus(pin) + port::kIn) & pin_mask(pin)) != 0;
}

}  // namespace hmc::samd21
