// Board devices (board.h). DRV8711 SPI: TI DRV8711 datasheet 7.5.1 ("Serial Data Format": 16-bit
// frames, MSB first, bit 15 = read, address in 14:12, data in 11:0; SCS active high; the data
// of a read is shifted out in bits 11:0 of the same frame; a write takes effect when SCS falls)
// and 7.6 (register reset values). STEP: a rising edge advances one microstep in the direction
// DIR gives (DIR high = reverse, as firmware/targets/samd21/step_pins.cpp drives it).
#include "board.h"

#include "../chip/chip.h"
#include "../chip/port.h"
#include "samd21_board_map.h"
#include "sim_board.h"

namespace hmc::emu {
namespace {

namespace pinmap = hmc::samd21::board;

bool bit(uint32_t word, unsigned n) { return (word & (1u << n)) != 0; }

// DRV8711 7.6: CTRL 0xC10, TORQUE 0x1FF, OFF 0x030, BLANK 0x080, DECAY 0x110, STALL 0x040,
// DRIVE 0xA59, STATUS 0x000.
constexpr std::array<uint16_t, 8> kDrvReset = {0xC10, 0x1FF, 0x030, 0x080,
                                               0x110, 0x040, 0xA59, 0x000};

}  // namespace


Board::Board(Chip& chip) : chip_(chip) {
  for (Drv8711& d : drivers_) d.regs = kDrvReset;
  for (unsigned m = 0; m < 3; ++m) axes_[m].position = config_[m].start;
}

void Board::set_axis(unsigned motor, const sim::AxisConfig& config) {
  config_[motor] = config;
  axes_[motor].position = config.start;
  update_limits(motor);
}

void Board::drive_switch(unsigned motor, unsigned end, bool pressed) {
  if (motor >= 2 || axes_[motor].pressed[end] == pressed) return;
  axes_[motor].pressed[end] = pressed;
  const pinmap::SwitchPin& sw = pinmap::kLimits[motor][end];
  chip_.port().drive(sw.pin.group, sw.pin.number, pressed ? (sw.active_low ? 0 : 1) : -1);
}

void Board::update_limits(unsigned motor) {
  if (motor >= 2) return;
  const bool at[2] = {config_[motor].has_switches && axes_[motor].position <= config_[motor].low_switch,
                      config_[motor].has_switches && axes_[motor].position >= config_[motor].high_switch};
  for (unsigned end = 0; end < 2; ++end) drive_switch(motor, end, held_[motor][end] < 0 ? at[end] : held_[motor][end] == 1);
}

void Board::hold_limit(unsigned motor, unsigned end, int held) {
  held_[motor][end] = held;
  update_limits(motor);
}

void Board::outputs_changed(unsigned group, uint32_t before, uint32_t after) {
  for (unsigned m = 0; m < 3; ++m) {
    const pinmap::DriverPins& pins = pinmap::kDrivers[m];
    if (pins.step.group == group && !bit(before, pins.step.number) &&
        bit(after, pins.step.number)) {
      const bool reverse = chip_.port().level(pins.dir.group, pins.dir.number);
      // DRV8711 CTRL.MODE (bits 6:3): 2^MODE microsteps per full step (7.6.1), so one STEP
      // edge moves 256 >> MODE in 1/256 step.
      const unsigned mode = (drivers_[m].regs[0] >> 3) & 0xF;
      const int64_t delta = mode <= 8 ? (256 >> mode) : 1;
      axes_[m].position += reverse ? -delta : delta;
      ++axes_[m].steps;
      update_limits(m);
    }
    if (pins.cs.group == group && bit(before, pins.cs.number) && !bit(after, pins.cs.number)) {
      Drv8711& d = drivers_[m];
      if (d.write_pending) {
        const unsigned address = (d.frame >> 12) & 7;
        const uint16_t data = d.frame & 0xFFF;
        // STATUS: writing 0 to a bit clears it; other registers take the value (7.6.8).
        d.regs[address] = address == 7 ? static_cast<uint16_t>(d.regs[7] & data) : data;
        d.write_pending = false;
      }
      d.received = 0;
    }
  }
}

uint8_t Board::spi_exchange(unsigned sercom, uint8_t mosi) {
  for (unsigned s = 0; s < 2; ++s) {
    if (pinmap::kLedStrips[s].sercom == sercom) {
      strip_bytes_[s].push_back(mosi);
      return 0;
    }
  }
  if (sercom != pinmap::driver_spi::kSercom) return 0;
  Drv8711* selected = nullptr;
  for (unsigned m = 0; m < 3; ++m) {
    const pinmap::Pin cs = pinmap::kDrivers[m].cs;
    if (chip_.port().level(cs.group, cs.number)) {
      if (selected != nullptr) return 0;  // two chips selected: both drive MISO; read as 0
      selected = &drivers_[m];
    }
  }
  if (selected == nullptr) return 0;
  Drv8711& d = *selected;
  if (d.received >= 2) return 0;  // bytes beyond the 16-bit frame are ignored
  d.frame = static_cast<uint16_t>(d.frame << 8 | mosi);
  if (d.received++ == 0) {
    const unsigned address = (mosi >> 4) & 7;
    return bit(mosi, 7) ? static_cast<uint8_t>((d.regs[address] >> 8) & 0x0F) : 0;
  }
  const unsigned address = (d.frame >> 12) & 7;
  if (bit(d.frame, 15)) return static_cast<uint8_t>(d.regs[address] & 0xFF);
  d.write_pending = true;
  return 0;
}

bool Board::set_switch(const std::string& name, bool pressed) {
  const pinmap::SwitchPin* sw = nullptr;
  if (name == "emergency") sw = &pinmap::kEmergency;
  if (name == "limit1-") sw = &pinmap::kLimits[0][0];
  if (name == "limit1+") sw = &pinmap::kLimits[0][1];
  if (name == "limit2-") sw = &pinmap::kLimits[1][0];
  if (name == "limit2+") sw = &pinmap::kLimits[1][1];
  if (sw == nullptr) return false;
  if (sw == &pinmap::kEmergency) emergency_ = pressed;
  // A pressed switch drives its pin to its active level; released, the pin is left to its pull.
  chip_.port().drive(sw->pin.group, sw->pin.number, pressed ? (sw->active_low ? 0 : 1) : -1);
  return true;
}

std::vector<uint8_t> Board::take_strip_bytes(unsigned strip) {
  std::vector<uint8_t> out;
  out.swap(strip_bytes_[strip]);
  return out;
}

}  // namespace hmc::emu
