// PORT and EIC (port.h).
#include "port.h"

#include "../board/board.h"

namespace hmc::emu {
namespace {

std::string pin_name(unsigned group, unsigned pin) {
  return std::string(group == 0 ? "PA" : "PB") + (pin < 10 ? "0" : "") + std::to_string(pin);
}

constexpr uint8_t kPmuxEn = 1, kInEn = 2, kPullEn = 4;

}  // namespace

// Datasheet 23.6.3.2/23.6.3.3: an output drives OUT; an input with PULLEN is pulled toward OUT;
// an input the board does not drive and no pull holds reads low here (it floats on silicon).
// A pin handed to a peripheral output (SERCOM pad, TC/TCC WO; 23.6.3.5 "Peripheral Multiplexing")
// is driven by it, whatever DIR and OUT say; an EIC line (function A) leaves it an input.
bool Port::level(unsigned group, unsigned pin) const {
  const Group& g = groups_[group];
  const uint32_t bit = 1u << pin;
  if ((g.pincfg[pin] & kPmuxEn) != 0) {
    const samd21::port_functions::Signal* signal = route(group, pin);
    if (signal != nullptr && signal->unit != samd21::port_functions::Unit::kEic) {
      return chip_.peripheral_output(signal->unit, signal->instance, signal->index);
    }
  }
  if ((g.dir & bit) != 0 && (g.pincfg[pin] & kPmuxEn) == 0) return (g.out & bit) != 0;
  if (g.external[pin] >= 0) return g.external[pin] != 0;
  if ((g.pincfg[pin] & kPullEn) != 0) return (g.out & bit) != 0;
  return false;
}

void Port::update_routes(unsigned group) {
  Group& g = groups_[group];
  for (unsigned pin = 0; pin < 32; ++pin) {
    g.routes[pin] = nullptr;
    if ((g.pincfg[pin] & kPmuxEn) == 0) continue;
    const char letter = static_cast<char>('A' + pmux(group, pin));
    for (const samd21::port_functions::Signal& s : samd21::port_functions::kSignals) {
      if (s.group == group && s.number == pin && s.letter == letter) g.routes[pin] = &s;
    }
  }
}

// IN reads the pin only where the input buffer is on (PINCFG.INEN, 23.8.13); 0 elsewhere.
uint32_t Port::live_in(unsigned group) const {
  uint32_t in = 0;
  for (unsigned pin = 0; pin < 32; ++pin) {
    if ((groups_[group].pincfg[pin] & kInEn) != 0 && level(group, pin)) in |= 1u << pin;
  }
  return in;
}

void Port::drive(unsigned group, unsigned pin, int level_or_release) {
  const bool before = level(group, pin);
  groups_[group].external[pin] = static_cast<int8_t>(level_or_release < 0 ? -1 : level_or_release != 0);
  const bool after = level(group, pin);
  if (before != after && (groups_[group].pincfg[pin] & kPmuxEn) != 0 && pmux(group, pin) == 0) {
    chip_.eic_line(pin % 16, after);  // function A: EXTINT[pin mod 16] (datasheet 7.1, table 7-1)
  }
}

uint32_t Port::access(uint32_t offset, uint32_t value, unsigned size, bool write, bool iobus) {
  const unsigned group = offset / 0x80;
  const uint32_t reg = offset % 0x80;
  if (group > 1) {
    chip_.violation("PORT group " + std::to_string(group) + " does not exist on the SAMD21G");
    return 0;
  }
  Group& g = groups_[group];
  if (!write) {
    if (touches(reg, size, 0x20, 4)) {
      const uint32_t live = live_in(group);
      uint32_t in = live;
      if (iobus) {
        // 23.6.2.6 / 23.5.9 "CPU Local Bus": the IOBUS cannot wait for the IN synchroniser, so a
        // pin read through it must have continuous sampling (CTRL.SAMPLING); otherwise the read
        // returns the value of the last on-demand sample, which may be stale.
        const uint32_t unsampled = ~g.ctrl;
        uint32_t inputs = 0;
        for (unsigned pin = 0; pin < 32; ++pin) {
          if ((g.pincfg[pin] & kInEn) != 0) inputs |= 1u << pin;
        }
        if ((inputs & unsampled) != 0) {
          std::string pins;
          for (unsigned pin = 0; pin < 32; ++pin) {
            if ((inputs & unsampled & (1u << pin)) != 0) pins += " " + pin_name(group, pin);
          }
          chip_.violation("IOBUS read of PORT IN while input pins have no continuous sampling "
                          "(PORT CTRL.SAMPLING clear; datasheet 23.6.2.6: the IOBUS read returns "
                          "stale data):" + pins);
        }
        in = (live & g.ctrl) | (g.sampled & ~g.ctrl);
      } else {
        g.sampled = live;  // an APB read of IN triggers on-demand sampling (23.6.2.6)
        chip_.charge_cycles(2);  // and waits for the synchroniser: 2 extra cycles
      }
      RegisterBytes view(4);
      view.set(0, in, 4);
      return view.get(reg - 0x20, size);
    }
    RegisterBytes view(0x60);
    view.set(0x00, g.dir, 4);
    view.set(0x04, g.dir, 4);
    view.set(0x08, g.dir, 4);
    view.set(0x0C, g.dir, 4);
    view.set(0x10, g.out, 4);
    view.set(0x14, g.out, 4);
    view.set(0x18, g.out, 4);
    view.set(0x1C, g.out, 4);
    view.set(0x24, g.ctrl, 4);
    for (unsigned i = 0; i < 16; ++i) view.set(0x30 + i, g.pmux[i], 1);
    for (unsigned i = 0; i < 32; ++i) view.set(0x40 + i, g.pincfg[i], 1);
    return view.get(reg, size);
  }
  chip_.before_port_write();
  const uint32_t old_out = g.out, old_dir = g.dir;
  // A narrower write lands in its bytes of the 32-bit register.
  const uint32_t shift = 8 * (reg % 4);
  const uint32_t mask = (size == 4 ? 0xFFFFFFFFu : ((1u << (8 * size)) - 1u)) << shift;
  const uint32_t v = (value << shift) & mask;
  switch (reg & ~3u) {
    case 0x00: g.dir = (g.dir & ~mask) | v; break;
    case 0x04: g.dir &= ~v; break;
    case 0x08: g.dir |= v; break;
    case 0x0C: g.dir ^= v; break;
    case 0x10: g.out = (g.out & ~mask) | v; break;
    case 0x14: g.out &= ~v; break;
    case 0x18: g.out |= v; break;
    case 0x1C: g.out ^= v; break;
    case 0x20: break;  // IN is read-only
    case 0x24: g.ctrl = (g.ctrl & ~mask) | v; break;
    case 0x28:
      chip_.violation("PORT WRCONFIG is not modelled");
      return 0;
    default:
      if (reg >= 0x30 && reg < 0x40) {
        for (unsigned i = 0; i < size; ++i) g.pmux[reg - 0x30 + i] = static_cast<uint8_t>(value >> (8 * i));
      } else if (reg >= 0x40 && reg < 0x60) {
        for (unsigned i = 0; i < size; ++i) g.pincfg[reg - 0x40 + i] = static_cast<uint8_t>(value >> (8 * i) & 0x47);
      }
  }
  if (g.out != old_out || g.dir != old_dir) outputs_changed(group, old_out, old_dir);
  // PMUX, PINCFG or DIR: a pin may carry another signal or level now.
  if (reg >= 0x30 && reg < 0x60) update_routes(group);
  if ((reg >= 0x30 && reg < 0x60) || g.dir != old_dir) chip_.board().routes_changed();
  return 0;
}

void Port::outputs_changed(unsigned group, uint32_t old_out, uint32_t) {
  chip_.board().outputs_changed(group, old_out, groups_[group].out);
}

// ---- EIC: CTRL 0x00, STATUS 0x01, INTENCLR 0x08, INTENSET 0x0C, INTFLAG 0x10, CONFIG0/1 0x18
// (datasheet 21.8). SENSE per line: 0 none, 1 rise, 2 fall, 3 both, 4 high, 5 low.

uint32_t Eic::read(uint32_t offset, unsigned size) {
  RegisterBytes view(0x20);
  view.set(0x00, ctrl_, 1);
  view.set(0x08, inten_, 4);
  view.set(0x0C, inten_, 4);
  view.set(0x10, intflag_, 4);
  view.set(0x18, config_[0], 4);
  view.set(0x1C, config_[1], 4);
  return view.get(offset, size);  // STATUS.SYNCBUSY reads 0: writes synchronise at once here
}

void Eic::write(uint32_t offset, uint32_t value, unsigned size) {
  RegisterBytes view(0x20);
  view.set(0x18, config_[0], 4);
  view.set(0x1C, config_[1], 4);
  view.set(offset, value, size);
  if (touches(offset, size, 0x18, 8)) {
    if (enabled()) {
      chip_.violation("write to EIC CONFIG while the EIC is enabled (datasheet 21.8.10: "
                      "enable-protected)");
      return;
    }
    config_[0] = view.get(0x18, 4);
    config_[1] = view.get(0x1C, 4);
  }
  if (touches(offset, size, 0x00, 1)) {
    const uint8_t v = static_cast<uint8_t>(view.get(0, 1));
    if ((v & 1) != 0) {  // SWRST: every register to its reset value (21.8.1)
      ctrl_ = 0;
      inten_ = intflag_ = config_[0] = config_[1] = 0;
    } else {
      ctrl_ = v & 2;
    }
  }
  if (touches(offset, size, 0x08, 4)) inten_ &= ~view.get(0x08, 4);
  if (touches(offset, size, 0x0C, 4)) inten_ |= view.get(0x0C, 4);
  if (touches(offset, size, 0x10, 4)) intflag_ &= ~view.get(0x10, 4);  // write 1 to clear
  chip_.irq_changed();
}

void Eic::line_changed(unsigned extint, bool level) {
  if (!enabled()) return;
  const unsigned sense = (config_[extint / 8] >> (4 * (extint % 8))) & 7;
  const bool fire = sense == 3 || (sense == 1 && level) || (sense == 2 && !level) ||
                    (sense == 4 && level) || (sense == 5 && !level);
  // The filter (FILTEN, 21.6.2.4) takes the majority of three GCLK_EIC samples: a clean edge
  // passes ~3 periods late; that delay is not modelled.
  if (fire) {
    intflag_ |= 1u << extint;
    chip_.irq_changed();
  }
}

}  // namespace hmc::emu
