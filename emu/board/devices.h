// What the devices on the emulated board's pins make of the levels the chip drives there: an
// SK6812 strip's data line decoded into GRBW per LED, a hobby servo's pulse train measured into
// pulse widths. Pure: they are fed level changes with their times (ps, non-decreasing) and know
// nothing of the chip; board.cpp feeds them from the pins, devices_test.cpp from test waveforms.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace hmc::emu {

// An SK6812 RGBW strip's data input (SK6812RGBW datasheet, as HARDWARE.md, "SK6812 RGBW strips",
// cites it): each bit starts with a rising edge; a high of 0.3 µs ± 0.15 µs is a 0 (T0H), of
// 0.6 µs ± 0.15 µs a 1 (T1H); the low after it is 0.9 µs (T0L) or 0.6 µs (T1L), ± 0.15 µs; a low
// of at least 80 µs (the reset code) latches what was received. Each LED keeps the first 32 bits
// that reach it (G, R, B, W, MSB first) and passes the rest on, so LED i holds bits 32i..32i+31.
class Sk6812Strip {
 public:
  static constexpr uint64_t kResetPs = 80000000;  // ≥ 80 µs low latches
  // The boundary between the T0H and T1H windows (0.45 µs: T0H's upper and T1H's lower end):
  // a longer high is read as a 1.
  static constexpr uint64_t kOneHighPs = 450000;
  static constexpr uint64_t kTolerancePs = 150000;

  struct Frame {
    uint64_t latched_ps = 0;
    std::vector<std::array<uint8_t, 4>> grbw;  // the whole strip after the latch
    uint32_t leds_written = 0;                 // LEDs that received all 32 bits
    uint32_t bits_left = 0;                    // bits of an incomplete last LED (dropped)
  };

  explicit Sk6812Strip(unsigned leds) : grbw_(leds, std::array<uint8_t, 4>{0, 0, 0, 0}) {}
  void level(bool high, uint64_t ps);
  // A frame whose reset gap has passed by `now_ps` is latched (at the gap's end).
  void poll(uint64_t now_ps);
  // When the pending frame latches, if the line stays low (UINT64_MAX: nothing pending).
  uint64_t latch_due_ps() const;
  std::vector<Frame> take_frames();
  bool has_frames() const { return !frames_.empty(); }
  // Bits whose high or low time fell outside its datasheet window (T0H/T1H/T0L/T1L ± 0.15 µs).
  uint64_t bits() const { return bits_total_; }
  uint64_t highs_off_window() const { return highs_off_; }
  uint64_t lows_off_window() const { return lows_off_; }

 private:
  void latch(uint64_t at_ps);

  std::vector<std::array<uint8_t, 4>> grbw_;
  std::vector<bool> received_;  // bits since the last latch
  bool high_ = false;
  uint64_t rise_ps_ = 0, fall_ps_ = 0;
  bool last_bit_ = false;
  std::vector<Frame> frames_;
  uint64_t bits_total_ = 0, highs_off_ = 0, lows_off_ = 0;
};

// A hobby servo's control input (arduino-libraries/Servo, as HARDWARE.md, "Servos", cites it): a
// pulse every 20 ms whose width sets the position. The width of each pulse is measured from its
// rising to its falling edge, to the nearest µs; a change of width is an event. A servo that
// gets no pulse for kReleasePs after the last one began has been let go (the seed detaches its
// servos): an event too. (30 ms, one and a half periods: the emulator's own threshold.)
class ServoInput {
 public:
  static constexpr uint64_t kReleasePs = 30000000000ull;

  struct Event {
    uint64_t ps = 0;         // the pulse's end, or when the release was noticed
    uint32_t pulse_us = 0;   // 0: released
  };

  void level(bool high, uint64_t ps);
  void poll(uint64_t now_ps);
  uint64_t release_due_ps() const;
  std::vector<Event> take_events();
  bool has_events() const { return !events_.empty(); }
  uint64_t pulses() const { return pulses_; }

 private:
  bool high_ = false;
  bool active_ = false;  // pulses are arriving
  uint64_t rise_ps_ = 0;
  uint32_t last_us_ = 0;
  uint64_t pulses_ = 0;
  std::vector<Event> events_;
};

}  // namespace hmc::emu
