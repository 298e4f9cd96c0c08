// The devices on the emulated board's pins, wired as firmware/targets/samd21/board.h says (the
// one pin map; the emulator reads the same header): three DRV8711 drivers on the SPI bus with
// their STEP/DIR inputs turned into axis positions, the switches, the servos on TCC0, the
// SK6812 strips on their SPI data lines.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sim_board.h"

namespace hmc::emu {

class Chip;

class Board {
 public:
  struct Axis {
    int64_t position = 0;  // 1/256 step, forward positive (hmc-sim's unit)
    uint64_t steps = 0;    // STEP rising edges seen
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
  uint8_t spi_exchange(unsigned sercom, uint8_t mosi);
  void servos_changed() {}
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
  const Drv8711& driver(unsigned chip) const { return drivers_[chip]; }
  // SK6812 bytes each strip's data line carried since the last take (raw SPI bytes).
  std::vector<uint8_t> take_strip_bytes(unsigned strip);

 private:
  void update_limits(unsigned motor);
  void drive_switch(unsigned motor, unsigned end, bool pressed);

  Chip& chip_;
  std::array<sim::AxisConfig, 3> config_ = sim::SimConfig{}.axes;
  std::array<Axis, 3> axes_{};
  int held_[2][2] = {{-1, -1}, {-1, -1}};  // hold_limit(): -1 follows the axis
  bool emergency_ = false;
  std::array<Drv8711, 3> drivers_{};
  std::array<std::vector<uint8_t>, 2> strip_bytes_{};
};

}  // namespace hmc::emu
