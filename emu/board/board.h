// The devices on the emulated board's pins, wired as firmware/targets/samd21/board.h says (the
// one pin map; the emulator reads the same header): three DRV8711 drivers on the SPI bus with
// their STEP/DIR inputs turned into axis positions, the switches, two servos and two SK6812
// strips and the buzzer, each seeing only what the chip really drives on its pin (the PMUX
// function, the peripheral's pad or output, the waveform with its timing), the booting LEDs.
// With a trace (trace.h) every event is written in hmc-sim's format.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "../chip/chip.h"
#include "devices.h"
#include "sim_board.h"
#include "trace.h"

namespace hmc::emu {

// One byte on an SPI master's data-out pad: when it started, the bit time, the pad, the order.
struct SpiBits {
  uint64_t start_ps;
  uint64_t bit_ps;
  unsigned data_out_pad;
  bool lsb_first;
};

class Board : public Timed {
 public:
  struct Axis {
    int64_t position = 0;  // 1/256 step, forward positive (hmc-sim's unit)
    uint64_t steps = 0;    // STEP rising edges seen
    // STEP's timing since the figures were last reset (reset_pulse_figures): the pulses that
    // ended, their shortest and longest high time, the shortest low time between two pulses,
    // the shortest and longest time between two rising edges (0 / UINT64_MAX: none yet).
    struct Pulses {
      uint64_t ended = 0;
      uint64_t high_min_ps = UINT64_MAX, high_max_ps = 0, low_min_ps = UINT64_MAX;
      uint64_t period_min_ps = UINT64_MAX, period_max_ps = 0;
    } pulses;
    uint64_t rise_ps = UINT64_MAX, fall_ps = UINT64_MAX;  // the last edges
    bool pressed[2] = {false, false};  // limit switch at end 0 (reverse), end 1 (forward)
  };
  struct Drv8711 {
    std::array<uint16_t, 8> regs{};
    uint8_t received = 0;  // bytes of the current 16-bit frame
    uint16_t frame = 0;
    bool write_pending = false;
  };

  explicit Board(Chip& chip);
  // PORT outputs changed (group, before, after).
  void outputs_changed(unsigned group, uint32_t before, uint32_t after);
  // One byte out of SERCOM `sercom`'s SPI master; returns the byte on MISO.
  uint8_t spi_exchange(unsigned sercom, uint8_t mosi, const SpiBits& bits);
  // A peripheral output (TCC WO[index]) changed level at `ps`.
  void peripheral_edge(samd21::port_functions::Unit unit, unsigned instance, unsigned index, bool level,
                       uint64_t ps);
  // PMUX or PINCFG changed: a device's pin may carry another signal now.
  void routes_changed();
  // TC3 was written: the buzzer's tone may have started, stopped or changed.
  void tone_source_changed();
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;
  void set_trace(Trace* trace) { trace_ = trace; }
  const Sk6812Strip& strip(unsigned index) const { return strips_[index]; }
  const ServoInput& servo(unsigned index) const { return servos_[index]; }
  // Motor `motor`'s (0..2) axis: its start and switch positions (hmc-sim's --axis); the axis
  // moves to its start. Default: hmc-sim's (sim::SimConfig).
  void set_axis(unsigned motor, const sim::AxisConfig& config);
  // Switches by name: "limit1-", "limit1+", "limit2-", "limit2+", "emergency".
  bool set_switch(const std::string& name, bool pressed);
  // Limit switch `end` of motor `motor` (0 or 1) held pressed (1) or open (0) wherever the axis
  // is, or following the axis again (-1) — hmc-sim's press/release/auto.
  void hold_limit(unsigned motor, unsigned end, int held);
  bool emergency() const { return emergency_; }
  // Latches DRV8711 STATUS bits of motor `motor`'s (0..2) driver, as a fault would (7.6.8:
  // the bits stay set until the firmware writes 0 to them).
  void latch_fault(unsigned motor, uint8_t bits) { drivers_[motor].regs[7] |= bits; }

  const Axis& axis(unsigned motor) const { return axes_[motor]; }
  void reset_pulse_figures() {
    for (Axis& a : axes_) a.pulses = Axis::Pulses{};
  }
  const Drv8711& driver(unsigned chip) const { return drivers_[chip]; }

 private:
  void update_limits(unsigned motor);
  void drive_switch(unsigned motor, unsigned end, bool pressed);

  // The device pins (strips 0-1, servos 2-3), each fed the level the chip drives there.
  void refresh_device_pins(uint64_t ps);
  void flush_devices();
  // A device's deadline may now come before the chip's next event: have the chip look again.
  void deadlines_changed();
  void traced(uint64_t ps, const std::string& fields) {
    if (trace_ != nullptr) trace_->event(ps, fields);
  }

  Chip& chip_;
  Trace* trace_ = nullptr;
  std::array<Sk6812Strip, 2> strips_;
  std::array<ServoInput, 2> servos_{};
  uint32_t tone_hz_ = 0;  // the buzzer's pin's frequency now (0: silent)
  uint64_t tone_since_ps_ = 0;
  std::array<bool, 2> boot_leds_{};   // as last traced
  uint64_t boot_leds_due_ps_ = UINT64_MAX;  // a change to trace once both pins settled
  uint64_t boot_leds_changed_ps_ = 0;
  std::array<sim::AxisConfig, 3> config_ = sim::SimConfig{}.axes;
  std::array<Axis, 3> axes_{};
  int held_[2][2] = {{-1, -1}, {-1, -1}};  // hold_limit(): -1 follows the axis
  bool emergency_ = false;
  std::array<Drv8711, 3> drivers_{};
};

}  // namespace hmc::emu
