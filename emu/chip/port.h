// PORT (GPIO, over the APB at 0x41004400 and the single-cycle IOBUS at 0x60000000) and EIC
// (external interrupts). The pin levels come from the outputs and from the board's devices
// (emu/board). SAMD21 datasheet (DS40001882) chapters 23 (PORT) and 21 (EIC).
#pragma once

#include <cstdint>
#include <string>

#include "../../firmware/targets/samd21/port_functions.h"
#include "chip.h"

namespace hmc::emu {

class Port : public Peripheral {
 public:
  explicit Port(Chip& chip) : chip_(chip) {}
  uint32_t read(uint32_t offset, unsigned size) override { return access(offset, 0, size, false, false); }
  void write(uint32_t offset, uint32_t value, unsigned size) override { access(offset, value, size, true, false); }
  // The IOBUS view (datasheet 23.5.9): the same registers, one cycle, no wait for the input
  // synchroniser.
  Peripheral& iobus() { return iobus_; }

  uint32_t out(unsigned group) const { return groups_[group].out; }
  uint32_t dir(unsigned group) const { return groups_[group].dir; }
  uint8_t pincfg(unsigned group, unsigned pin) const { return groups_[group].pincfg[pin]; }
  unsigned pmux(unsigned group, unsigned pin) const {
    return (groups_[group].pmux[pin / 2] >> (4 * (pin & 1))) & 0xF;
  }
  bool level(unsigned group, unsigned pin) const;
  // The peripheral signal a pin is handed to: PINCFG.PMUXEN set, PMUX's function looked up in the
  // datasheet's multiplexing table (Table 7-1, firmware/targets/samd21/port_functions.h). nullptr:
  // a GPIO, or a function the table does not list for this pin (it carries no modelled signal).
  const samd21::port_functions::Signal* route(unsigned group, unsigned pin) const {
    return groups_[group].routes[pin];
  }
  // The board drives (or releases, level -1) an input pin.
  void drive(unsigned group, unsigned pin, int level);

 private:
  struct Group {
    uint32_t dir = 0, out = 0, ctrl = 0, sampled = 0;
    uint8_t pmux[16] = {};
    uint8_t pincfg[32] = {};
    const samd21::port_functions::Signal* routes[32] = {};  // route(), kept at PMUX/PINCFG writes
    int8_t external[32];
    Group() {
      for (int8_t& e : external) e = -1;
    }
  };
  class Iobus : public Peripheral {
   public:
    explicit Iobus(Port& port) : port_(port) {}
    uint32_t read(uint32_t offset, unsigned size) override { return port_.access(offset, 0, size, false, true); }
    void write(uint32_t offset, uint32_t value, unsigned size) override { port_.access(offset, value, size, true, true); }

   private:
    Port& port_;
  };
  uint32_t access(uint32_t offset, uint32_t value, unsigned size, bool write, bool iobus);
  uint32_t live_in(unsigned group) const;
  void update_routes(unsigned group);
  void outputs_changed(unsigned group, uint32_t old_out, uint32_t old_dir);

  Chip& chip_;
  Group groups_[2];
  Iobus iobus_{*this};
};

class Eic : public Peripheral {
 public:
  explicit Eic(Chip& chip) : chip_(chip) {}
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  bool irq() const { return (intflag_ & inten_) != 0; }
  // A pin handed to the EIC (function A) changed level.
  void line_changed(unsigned extint, bool level);

 private:
  bool enabled() const { return (ctrl_ & 2) != 0; }
  Chip& chip_;
  uint8_t ctrl_ = 0;
  uint32_t inten_ = 0, intflag_ = 0, config_[2] = {0, 0};
};

}  // namespace hmc::emu
