// Board devices (board.h). DRV8711 SPI: TI DRV8711 datasheet 7.5.1 ("Serial Data Format": 16-bit
// frames, MSB first, bit 15 = read, address in 14:12, data in 11:0; SCS active high; the data
// of a read is shifted out in bits 11:0 of the same frame; a write takes effect when SCS falls)
// and 7.6 (register reset values). STEP: a rising edge advances one microstep in the direction
// DIR gives (DIR high = reverse, as firmware/targets/samd21/step_pins.cpp drives it).
// SK6812 strips and servos: devices.h, fed the level of their pin whenever it may change (a GPIO
// write, a PMUX/PINCFG change, a TCC output edge, an SPI byte on the pad the pin carries). The
// buzzer sounds at the frequency of TC3's WO[0] while its pin carries that signal (TC3 in
// match-frequency mode toggles WO[0] at each CC0 match, datasheet 30.6.2.6: f = f_TC / (2 ·
// (CC0 + 1))).
#include "board.h"

#include <algorithm>

#include "../chip/chip.h"
#include "../chip/port.h"
#include "../chip/timers.h"
#include "samd21_board_map.h"
#include "sim_board.h"

namespace hmc::emu {
namespace {

namespace pinmap = hmc::samd21::board;
using samd21::port_functions::Signal;
using samd21::port_functions::Unit;

bool bit(uint32_t word, unsigned n) { return (word & (1u << n)) != 0; }

constexpr pinmap::Pin kStripPins[2] = {pinmap::kLedStrips[0].data, pinmap::kLedStrips[1].data};

bool routed_to(const Signal* signal, Unit unit, unsigned instance, unsigned index) {
  return signal != nullptr && signal->unit == unit && signal->instance == instance && signal->index == index;
}

std::string led_fields(unsigned strip, const Sk6812Strip::Frame& frame) {
  const std::array<uint8_t, 4>& first = frame.grbw[0];
  std::string fields = "\"ev\":\"led\",\"strip\":" + std::to_string(strip) +
                       ",\"r\":" + std::to_string(first[1]) + ",\"g\":" + std::to_string(first[0]) +
                       ",\"b\":" + std::to_string(first[2]) + ",\"w\":" + std::to_string(first[3]);
  // hmc-sim's event says one colour for the strip; anything else the bitstream did is added.
  uint32_t differing = 0;
  for (const auto& led : frame.grbw) differing += led != first ? 1u : 0u;
  if (differing != 0) fields += ",\"differing\":" + std::to_string(differing);
  if (frame.leds_written != frame.grbw.size()) fields += ",\"leds\":" + std::to_string(frame.leds_written);
  if (frame.bits_left != 0) fields += ",\"bits_left\":" + std::to_string(frame.bits_left);
  return fields;
}

// DRV8711 7.6: CTRL 0xC10, TORQUE 0x1FF, OFF 0x030, BLANK 0x080, DECAY 0x110, STALL 0x040,
// DRIVE 0xA59, STATUS 0x000.
constexpr std::array<uint16_t, 8> kDrvReset = {0xC10, 0x1FF, 0x030, 0x080,
                                               0x110, 0x040, 0xA59, 0x000};

}  // namespace

Board::Board(Chip& chip)
    : chip_(chip), strips_{Sk6812Strip(pinmap::kLedsPerStrip), Sk6812Strip(pinmap::kLedsPerStrip)} {
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
  traced(chip_.now_ps(), "\"ev\":\"switch\",\"motor\":" + std::to_string(motor + 1) + ",\"end\":" +
                             std::to_string(end) + ",\"pressed\":" + json_flag(pressed));
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
  const uint64_t at_ps = chip_.access_ps();  // a DMA beat's own time (chip.h)
  for (unsigned m = 0; m < 3; ++m) {
    const pinmap::DriverPins& pins = pinmap::kDrivers[m];
    Axis::Pulses& pulses = axes_[m].pulses;
    if (pins.step.group == group && bit(before, pins.step.number) && !bit(after, pins.step.number)) {
      Axis& a = axes_[m];
      const uint64_t high = at_ps - a.rise_ps;
      pulses.high_min_ps = std::min(pulses.high_min_ps, high);
      pulses.high_max_ps = std::max(pulses.high_max_ps, high);
      ++pulses.ended;
      a.fall_ps = at_ps;
    }
    if (pins.step.group == group && !bit(before, pins.step.number) &&
        bit(after, pins.step.number)) {
      Axis& a = axes_[m];
      if (a.fall_ps != UINT64_MAX && a.rise_ps != UINT64_MAX) {
        pulses.low_min_ps = std::min(pulses.low_min_ps, at_ps - a.fall_ps);
        const uint64_t period = at_ps - a.rise_ps;
        pulses.period_min_ps = std::min(pulses.period_min_ps, period);
        pulses.period_max_ps = std::max(pulses.period_max_ps, period);
      }
      a.rise_ps = at_ps;
      const bool reverse = chip_.port().level(pins.dir.group, pins.dir.number);
      // DRV8711 CTRL.MODE (bits 6:3): 2^MODE microsteps per full step (7.6.1), so one STEP
      // edge moves 256 >> MODE in 1/256 step.
      const unsigned mode = (drivers_[m].regs[0] >> 3) & 0xF;
      const int64_t delta = mode <= 8 ? (256 >> mode) : 1;
      axes_[m].position += reverse ? -delta : delta;
      ++axes_[m].steps;
      if (trace_ != nullptr) {  // the hot path: no strings built for a trace nobody reads
        traced(at_ps, "\"ev\":\"step\",\"motor\":" + std::to_string(m + 1) +
                                   ",\"pos\":" + std::to_string(axes_[m].position));
      }
      update_limits(m);
    }
    if (pins.dir.group == group && bit(before, pins.dir.number) != bit(after, pins.dir.number)) {
      traced(chip_.now_ps(), "\"ev\":\"dir\",\"motor\":" + std::to_string(m + 1) +
                                 ",\"reverse\":" + json_flag(bit(after, pins.dir.number)));
    }
    if (pins.cs.group == group && bit(before, pins.cs.number) && !bit(after, pins.cs.number)) {
      Drv8711& d = drivers_[m];
      if (d.write_pending) {
        const unsigned address = (d.frame >> 12) & 7;
        const uint16_t data = d.frame & 0xFFF;
        // STATUS: writing 0 to a bit clears it; other registers take the value (7.6.8).
        const uint16_t ctrl_before = d.regs[0];
        d.regs[address] = address == 7 ? static_cast<uint16_t>(d.regs[7] & data) : data;
        if (address == 0 && d.regs[0] != ctrl_before) {
          // CTRL: ENBL bit 0, MODE bits 6:3 (2^MODE microsteps per full step; 7.6.1).
          traced(chip_.now_ps(), "\"ev\":\"driver\",\"motor\":" + std::to_string(m + 1) +
                                     ",\"enabled\":" + json_flag(bit(d.regs[0], 0)) + ",\"microstep\":" +
                                     std::to_string(1u << ((d.regs[0] >> 3) & 0xF)));
        }
        d.write_pending = false;
      }
      d.received = 0;
    }
  }
  const pinmap::Pin leds[2] = {pinmap::kBootLedLeft, pinmap::kBootLedRight};
  for (const pinmap::Pin& led : leds) {
    if (led.group == group && bit(before, led.number) != bit(after, led.number) &&
        boot_leds_due_ps_ == UINT64_MAX) {
      // The image sets the two pins one after the other: the pair is traced once both settled.
      boot_leds_changed_ps_ = chip_.now_ps();
      boot_leds_due_ps_ = boot_leds_changed_ps_ + 1000000;  // 1 µs
      deadlines_changed();
    }
  }
  // The servo and strip pins, when this write changed one of them (STEP edges do not).
  uint32_t device_pins = 0;
  for (const pinmap::Pin& pin : {kStripPins[0], kStripPins[1], pinmap::servo::kPins[0], pinmap::servo::kPins[1]}) {
    if (pin.group == group) device_pins |= 1u << pin.number;
  }
  if (((before ^ after) & device_pins) != 0) refresh_device_pins(chip_.now_ps());
}

void Board::refresh_device_pins(uint64_t ps) {
  Port& port = chip_.port();
  for (unsigned s = 0; s < 2; ++s) {
    // A pin on a SERCOM pad gets its levels bit by bit from spi_exchange(), with their times.
    const Signal* route = port.route(kStripPins[s].group, kStripPins[s].number);
    if (route != nullptr && route->unit == Unit::kSercom) continue;
    strips_[s].level(port.level(kStripPins[s].group, kStripPins[s].number), ps);
  }
  for (unsigned s = 0; s < 2; ++s) {
    const pinmap::Pin pin = pinmap::servo::kPins[s];
    servos_[s].level(port.level(pin.group, pin.number), ps);
  }
  deadlines_changed();
}

void Board::deadlines_changed() {
  if (next_event_ps() < chip_.next_event_ps()) chip_.reschedule();
}

void Board::routes_changed() {
  refresh_device_pins(chip_.now_ps());
  tone_source_changed();
}

void Board::peripheral_edge(Unit unit, unsigned instance, unsigned index, bool level, uint64_t ps) {
  Port& port = chip_.port();
  for (unsigned s = 0; s < 2; ++s) {
    const pinmap::Pin pin = pinmap::servo::kPins[s];
    if (routed_to(port.route(pin.group, pin.number), unit, instance, index)) servos_[s].level(level, ps);
  }
  for (unsigned s = 0; s < 2; ++s) {
    if (routed_to(port.route(kStripPins[s].group, kStripPins[s].number), unit, instance, index)) {
      strips_[s].level(level, ps);
    }
  }
  deadlines_changed();
}

void Board::tone_source_changed() {
  const pinmap::Pin pin = pinmap::buzzer::kPin;
  // TC3's WO[0] reaches the buzzer only through the pin's PMUX function (Table 7-1: PA14 E).
  const bool routed = routed_to(chip_.port().route(pin.group, pin.number), Unit::kTc, 3, 0);
  const uint32_t hz = routed ? static_cast<uint32_t>(chip_.tc3().output_hz()) : 0;
  if (hz == tone_hz_) return;
  const uint64_t now = chip_.now_ps();
  if (tone_hz_ != 0) {
    // hmc-sim traces a tone when it is asked for, with its length; here the tone is known once
    // it ends: it is written then, with the time it began.
    traced(tone_since_ps_, "\"ev\":\"tone\",\"hz\":" + std::to_string(tone_hz_) + ",\"ms\":" +
                               std::to_string((now - tone_since_ps_ + 500000000) / 1000000000));
  }
  tone_hz_ = hz;
  tone_since_ps_ = now;
}

void Board::flush_devices() {
  for (unsigned s = 0; s < 2; ++s) {
    if (!strips_[s].has_frames() && !servos_[s].has_events()) continue;
    for (const Sk6812Strip::Frame& frame : strips_[s].take_frames()) traced(frame.latched_ps, led_fields(s + 1, frame));
    for (const ServoInput::Event& e : servos_[s].take_events()) {
      traced(e.ps, e.pulse_us == 0 ? "\"ev\":\"servo\",\"servo\":" + std::to_string(s + 1) + ",\"released\":true"
                                   : "\"ev\":\"servo\",\"servo\":" + std::to_string(s + 1) +
                                         ",\"pulse_us\":" + std::to_string(e.pulse_us));
    }
  }
}

void Board::advance(uint64_t now_ps) {
  for (Sk6812Strip& strip : strips_) strip.poll(now_ps);
  for (ServoInput& servo : servos_) servo.poll(now_ps);
  if (boot_leds_due_ps_ <= now_ps) {
    const std::array<bool, 2> now = {
        chip_.port().level(pinmap::kBootLedLeft.group, pinmap::kBootLedLeft.number),
        chip_.port().level(pinmap::kBootLedRight.group, pinmap::kBootLedRight.number)};
    if (now != boot_leds_) {
      boot_leds_ = now;
      traced(boot_leds_changed_ps_, std::string("\"ev\":\"boot_leds\",\"left\":") + json_flag(now[0]) +
                                        ",\"right\":" + json_flag(now[1]));
    }
    boot_leds_due_ps_ = UINT64_MAX;
  }
  flush_devices();
}

uint64_t Board::next_event_ps() const {
  uint64_t next = boot_leds_due_ps_;
  for (const Sk6812Strip& strip : strips_) next = std::min(next, strip.latch_due_ps());
  for (const ServoInput& servo : servos_) next = std::min(next, servo.release_due_ps());
  return next;
}

uint8_t Board::spi_exchange(unsigned sercom, uint8_t mosi, const SpiBits& bits) {
  // A strip sees the byte only if its pin carries this SERCOM's data-out pad (PMUX function and
  // pad from Table 7-1, the pad from CTRLA.DOPO): its bits, each held for a bit time.
  for (unsigned s = 0; s < 2; ++s) {
    if (!routed_to(chip_.port().route(kStripPins[s].group, kStripPins[s].number), Unit::kSercom, sercom,
                   bits.data_out_pad)) {
      continue;
    }
    for (unsigned i = 0; i < 8; ++i) {
      const bool level = ((mosi >> (bits.lsb_first ? i : 7 - i)) & 1) != 0;
      strips_[s].level(level, bits.start_ps + i * bits.bit_ps);
    }
    deadlines_changed();
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
  if (sw == &pinmap::kEmergency) {
    emergency_ = pressed;
    traced(chip_.now_ps(), std::string("\"ev\":\"emergency\",\"pressed\":") + json_flag(pressed));
  }
  for (unsigned motor = 0; motor < 2; ++motor) {
    for (unsigned end = 0; end < 2; ++end) {
      if (sw != &pinmap::kLimits[motor][end]) continue;
      traced(chip_.now_ps(), "\"ev\":\"switch\",\"motor\":" + std::to_string(motor + 1) + ",\"end\":" +
                                 std::to_string(end) + ",\"pressed\":" + json_flag(pressed));
    }
  }
  // A pressed switch drives its pin to its active level; released, the pin is left to its pull.
  chip_.port().drive(sw->pin.group, sw->pin.number, pressed ? (sw->active_low ? 0 : 1) : -1);
  return true;
}

}  // namespace hmc::emu
