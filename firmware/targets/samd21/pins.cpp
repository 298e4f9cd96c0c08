// GPIO and pin multiplexing (pins.h). PORT layout: SAMD21 datasheet, "PORT" (PINCFG one byte per
// pin; PMUX one byte per pin pair, even pin in bits 3:0, odd pin in bits 7:4).
#include "pins.h"

namespace hmc::samd21 {
namespace {

uint32_t group_base(board::Pin pin) { return port::kBase + port::kGroupStride * pin.group; }
uint32_t pincfg(board::Pin pin) { return group_base(pin) + port::kPinCfg + pin.number; }

// pin_read() reads IN through the IOBUS, which cannot wait for the input synchroniser: the
// datasheet ("PORT", CPU Local Bus) requires continuous sampling (CTRL.SAMPLING) for every pin
// read that way, or the value is stale. Every pin whose input buffer is turned on gets it.
void sample_continuously(board::Pin pin) {
  r32(group_base(pin) + port::kCtrl) = r32(group_base(pin) + port::kCtrl) | pin_mask(pin);
}

}  // namespace

void pin_output(board::Pin pin, bool high) {
  pin_set(pin, high);
  r8(pincfg(pin)) = 0;  // GPIO, input buffer off, no pull
  r32(group_base(pin) + port::kDirSet) = pin_mask(pin);
}

void pin_input(board::Pin pin, bool pull_up) {
  r32(group_base(pin) + port::kDirClr) = pin_mask(pin);
  if (pull_up) {
    pin_set(pin, true);  // with PULLEN, OUT = 1 selects the pull-up
    r8(pincfg(pin)) = static_cast<uint8_t>(port::kPinCfgInEn | port::kPinCfgPullEn);
  } else {
    r8(pincfg(pin)) = static_cast<uint8_t>(port::kPinCfgInEn);
  }
  sample_continuously(pin);
}

void pin_function(board::Pin pin, port::Function function) {
  const uint32_t pmux = group_base(pin) + port::kPmux + pin.number / 2u;
  const uint32_t shift = (pin.number & 1u) != 0 ? 4u : 0u;
  r8(pmux) = static_cast<uint8_t>((r8(pmux) & ~(0xFu << shift)) |
                                  (static_cast<uint32_t>(function) << shift));
  set8(pincfg(pin), port::kPinCfgPmuxEn);
}

void pin_sense(board::Pin pin) {
  set8(pincfg(pin), port::kPinCfgInEn);
  sample_continuously(pin);
}

void pin_release(board::Pin pin) { clear8(pincfg(pin), port::kPinCfgPmuxEn); }

}  // namespace hmc::samd21
