// Switches (switches.h). EIC setup: SAMD21 datasheet "EIC" (CONFIGn hold 4 bits per line: SENSE
// 2:0, FILTEN 3; they may be written only while the EIC is disabled).
#include "switches.h"

#include "board.h"
#include "clocks.h"
#include "irq.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_port.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

void sync() { wait_clear8(eic::kStatus, eic::kSyncBusy); }

bool pressed(const board::SwitchPin& sw) { return pin_read(sw.pin) != sw.active_low; }

uint32_t line_mask() {
  uint32_t mask = 1u << board::kEmergency.extint;
  for (const auto& motor : board::kLimits) {
    for (const board::SwitchPin& sw : motor) mask |= 1u << sw.extint;
  }
  return mask;
}

void configure(const board::SwitchPin& sw) {
  pin_input(sw.pin, true);
  pin_function(sw.pin, port::Function::kA_Eic);
  const uint32_t config = eic::kConfig0 + 4u * (sw.extint / 8u);
  const uint32_t shift = 4u * (sw.extint % 8u);
  r32(config) = (r32(config) & ~(0xFu << shift)) |
                ((eic::kSenseBoth | eic::kFilterEnable) << shift);
}

}  // namespace

void Switches::init() {
  set32(pm::kApbAMask, pm::kApbAEic);
  clock_connect(gclk::kIdEic, kGclkSlow32k);
  r8(eic::kCtrl) = static_cast<uint8_t>(eic::kSwRst);
  while ((r8(eic::kCtrl) & eic::kSwRst) != 0) {
  }
  sync();
  for (const auto& motor : board::kLimits) {
    for (const board::SwitchPin& sw : motor) configure(sw);
  }
  configure(board::kEmergency);
  const uint32_t mask = line_mask();
  r32(eic::kIntFlag) = mask;
  r32(eic::kIntEnSet) = mask;
  nvic_set_priority(irqn::kEic, board::kPrioritySwitches);
  nvic_unpend(irqn::kEic);
  nvic_enable(irqn::kEic);
  r8(eic::kCtrl) = static_cast<uint8_t>(eic::kEnable);
  sync();
}

bool Switches::limit_pressed(uint8_t motor, uint8_t end) const {
  if (motor < 1 || motor > 2 || end > 1) return false;  // motor 3 has no switches
  return pressed(board::kLimits[motor - 1][end]);
}

bool Switches::emergency_pressed() const { return pressed(board::kEmergency); }

void Switches::take_interrupt() { r32(eic::kIntFlag) = r32(eic::kIntFlag) & line_mask(); }

}  // namespace hmc::samd21
