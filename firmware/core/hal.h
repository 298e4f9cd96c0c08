// The hardware the firmware core drives, as small interfaces. The core never includes a
// hardware header: the SAMD21 target implements these with registers, the simulator with a
// virtual board. Calls made from the step interrupt are marked; they must be short and
// allocation-free in every implementation.
#pragma once

#include <stdint.h>

namespace hmc::hal {

// Time in ticks of the step timer since boot. 48 MHz: the SAMD21's core clock, so a tick is
// the finest step-time resolution the board can produce. 64 bits never wrap (12 000 years).
using Ticks = uint64_t;
inline constexpr uint32_t kTicksPerSecond = 48000000;
inline constexpr uint32_t kTicksPerMicrosecond = kTicksPerSecond / 1000000;

// The free-running step clock, and the step interrupt's compares (one a motor on the board;
// the simulator's one timer stands for them: StepScheduler::on_step_timer).
class StepTimer {
 public:
  virtual ~StepTimer() = default;
  virtual Ticks now() const = 0;
  // Asks for on_step_timer() (see StepScheduler) at `when`; a time already past fires at once.
  virtual void schedule(Ticks when) = 0;
  // Called from the step interrupt: returns once the clock has reached `when` (the end of a
  // STEP pulse, at most 2 µs away). The simulator's interrupt takes no time, so it only notes it.
  virtual void wait_until(Ticks when) { (void)when; }
};

// STEP and DIR lines of the three drivers; motor is 1..3. Called from the step interrupt.
class StepPins {
 public:
  virtual ~StepPins() = default;
  virtual void set_dir(uint8_t motor, bool reverse) = 0;
  virtual void set_step(uint8_t motor, bool high) = 0;
};

// The SPI bus to the DRV8711 drivers: one 16-bit transfer with the chip's select held
// (active high) for its duration; returns the word clocked in.
class SpiBus {
 public:
  virtual ~SpiBus() = default;
  virtual uint16_t transfer16(uint8_t chip, uint16_t word) = 0;
};

// Servo pulse outputs; servo is 1 (pan) or 2 (tilt).
class ServoPwm {
 public:
  virtual ~ServoPwm() = default;
  // Starts a 50 Hz pulse train of `pulse_us` microseconds.
  virtual void set_pulse(uint8_t servo, uint16_t pulse_us) = 0;
  // Stops the pulse train (the servo holds by friction and stops jittering).
  virtual void release(uint8_t servo) = 0;
};

// The two SK6812 RGBW strips, each set to one colour.
class LedStrips {
 public:
  virtual ~LedStrips() = default;
  virtual void set_color(uint8_t strip, uint8_t r, uint8_t g, uint8_t b, uint8_t w) = 0;
};

// Limit switches (two per motor for motors 1-2: `end` 0 toward reverse, 1 toward forward) and
// the emergency switch. True means pressed.
class Switches {
 public:
  virtual ~Switches() = default;
  virtual bool limit_pressed(uint8_t motor, uint8_t end) const = 0;
  virtual bool emergency_pressed() const = 0;
};

// The buzzer: a tone of `hz` for `ms`, not blocking.
class Buzzer {
 public:
  virtual ~Buzzer() = default;
  virtual void tone(uint16_t hz, uint16_t ms) = 0;
};

// The two booting LEDs on the board.
class BootLeds {
 public:
  virtual ~BootLeds() = default;
  virtual void set(bool left_on, bool right_on) = 0;
};

// The command serial line: bytes in (already buffered by the receive interrupt) and out.
class SerialPort {
 public:
  virtual ~SerialPort() = default;
  // The next received byte, or -1 when none is waiting.
  virtual int read_byte() = 0;
  virtual void write(const uint8_t* bytes, uint32_t count) = 0;
};

}  // namespace hmc::hal
