// SimBoard: the firmware core on a simulated board, on a virtual clock.
//
// The board is the real Controller (controller.h) wired to simulated hardware: a 48 MHz step
// timer whose interrupt runs at exactly the tick it was set for (and at once, preempting the
// main loop, for a time already past, as the SAMD21 port pends it); three axes that move when
// their DRV8711 is enabled, by 256/microstep position units per STEP rising edge, the
// microstep read from the MODE bits the core wrote over SPI; limit switches that close at
// configured positions; servos, LED strips, buzzer, booting LEDs; a UART whose bytes cross the
// line both ways at the pace of an emulated baud rate.
//
// The main loop (Controller::poll) runs after every received byte, after every switch change,
// and every kPollTicks otherwise. Nothing here reads the wall clock: run_until() advances
// virtual time as far as asked, processing events in time order, so results are exact and
// repeatable. hmc-sim (sim_main.cpp) maps virtual time to real time, or runs as fast as possible.
//
// Trace: with set_trace(), every event is written as one JSON object per line:
//   {"t":T,"ev":"step","motor":M,"pos":P}          STEP rising edge; P after it (1/256 step)
//   {"t":T,"ev":"dir","motor":M,"reverse":B}
//   {"t":T,"ev":"driver","motor":M,"enabled":B,"microstep":N}   a CTRL write
//   {"t":T,"ev":"switch","motor":M,"end":E,"pressed":B}
//   {"t":T,"ev":"emergency","pressed":B}
//   {"t":T,"ev":"servo","servo":S,"pulse_us":U}   / {"t":T,"ev":"servo","servo":S,"released":true}
//   {"t":T,"ev":"led","strip":S,"r":R,"g":G,"b":B,"w":W}
//   {"t":T,"ev":"tone","hz":H,"ms":MS}
//   {"t":T,"ev":"boot_leds","left":B,"right":B}
//   {"t":T,"ev":"rx","line":"…"}  a line the board received;  {"t":T,"ev":"tx","line":"…"} sent
//   (at the firmware's write of its end; its bytes then cross the line at the baud rate)
// T is the virtual time in timer ticks (48 per µs) since power-up.
#pragma once

#include <stdint.h>

#include <array>
#include <deque>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "core/controller.h"
#include "core/hal.h"

namespace hmc::sim {

using hal::Ticks;

inline constexpr Ticks kNever = ~Ticks{0};
inline constexpr Ticks kPollTicks = 100 * hal::kTicksPerMicrosecond;  // main loop at least every 100 µs

struct AxisConfig {
  bool has_switches = false;
  int32_t start = 0;        // position at power-up (1/256 step)
  int32_t low_switch = 0;   // switch end 0 is pressed at or below this position
  int32_t high_switch = 0;  // switch end 1 is pressed at or above this position
};

struct SimConfig {
  // Motors 1-2: switches at 0 and 8 turns (409 600 = 1 600 full steps), starting mid-travel.
  // Motor 3 has none.
  std::array<AxisConfig, 3> axes{{{true, 204800, 0, 409600}, {true, 204800, 0, 409600}, {}}};
  fw::ControllerOptions options{};
  std::array<uint32_t, 3> accel{};  // steps/s² per motor
  uint32_t baud = 0;                // both ways; 0: bytes cross at once, else 10 bits per byte
  // What the boot event (EVR) says caused the reset: a simulated board is powered on, unless a
  // test asks for another cause (--reset-cause).
  proto::ResetCause reset_cause = proto::ResetCause::kPowerOn;
};

// A motor state's name in traces, status lines and behaviour vectors.
const char* state_name(fw::MotorState state);

// One switch's forced state, for injected events.
enum class Force : uint8_t { kNone, kPressed, kReleased };

class SimBoard {
 public:
  explicit SimBoard(const SimConfig& config);
  ~SimBoard();
  SimBoard(const SimBoard&) = delete;
  SimBoard& operator=(const SimBoard&) = delete;

  // Powers the board up at time 0: Controller::boot() with the configured reset cause.
  void boot();

  Ticks now() const { return now_; }
  // The next time anything happens on its own (timer, byte through the line either way, main
  // loop); never kNever.
  Ticks next_event() const;
  // Runs the board until virtual time `t` (no-op for a time already past).
  void run_until(Ticks t);
  void run_for(Ticks ticks) { run_until(now_ + ticks); }
  // True while a motor moves, a move waits, or bytes are still on the line either way.
  bool busy() const;
  // True while sent bytes are still on the wire or not yet read by the firmware.
  bool receiving() const { return !line_in_.empty() || !uart_rx_.empty(); }
  // True while bytes the firmware wrote are still on the wire.
  bool transmitting() const { return !line_out_.empty(); }

  // Host → board: bytes queued on the line from now, at the emulated baud rate.
  void send(const std::string& bytes);
  // Board → host: the bytes whose stop bit has passed since the last call. The firmware's
  // writes leave one byte per 10 bit times, each after the one before, from when it wrote them.
  std::string take_output();
  // When take_output() next has a byte: now() if it has one, else when the next byte on the
  // wire is through; kNever when every byte written has been taken.
  Ticks next_output() const;
  // Every byte the firmware has written and nobody has taken, on the wire or through it: for
  // checks of what the firmware answered at the moment it answered (the controller fuzzer),
  // rather than of what a host has read.
  std::string take_written();
  // Forgets every byte written, taken or not (a host that was not listening never reads them);
  // the wire stays busy until they would have been through.
  void drop_output();

  // Injected events (take effect now, as a switch interrupt would).
  void force_limit(uint8_t motor, uint8_t end, Force force);
  void set_emergency(bool pressed);
  // Latches DRV8711 STATUS bits of a driver (a fault the firmware finds when it reads STATUS).
  void set_driver_fault(uint8_t motor, uint8_t status_bits);

  // Observations.
  const fw::Controller& controller() const { return *controller_; }
  int32_t axis_position(uint8_t motor) const;   // physical, 1/256 step
  uint32_t steps(uint8_t motor) const;          // STEP rising edges since power-up
  bool limit_pressed(uint8_t motor, uint8_t end) const;
  bool emergency_pressed() const { return emergency_; }
  uint16_t servo_pulse(uint8_t servo) const;    // µs, 0 when released
  uint16_t servo_last_pulse(uint8_t servo) const;  // µs of the last pulse train, even if released
  std::array<uint8_t, 4> led(uint8_t strip) const;  // r, g, b, w
  std::array<bool, 2> boot_leds() const { return boot_leds_; }  // left, right
  struct Tone {
    Ticks t;
    uint16_t hz;
    uint16_t ms;
  };
  const std::vector<Tone>& tones() const { return tones_; }
  uint16_t driver_register(uint8_t motor, uint8_t address) const;
  uint32_t driver_microstep(uint8_t motor) const;
  bool driver_enabled(uint8_t motor) const;
  // Rising-edge times of every step since record_steps(true), per motor.
  void record_steps(bool on) { record_steps_ = on; }
  const std::vector<Ticks>& step_times(uint8_t motor) const { return step_times_[motor - 1]; }
  void clear_step_times();

  // JSON-lines trace (see above); null turns it off.
  void set_trace(std::ostream* out) { trace_ = out; }

 private:
  class Hardware;  // implements every HAL interface over this board's state
  friend class Hardware;

  struct Axis {
    AxisConfig config;
    int32_t position = 0;
    bool reverse = false;
    bool step_high = false;
    uint32_t steps = 0;
    bool pressed[2] = {false, false};
    Force force[2] = {Force::kNone, Force::kNone};
  };
  struct Arrival {
    Ticks at;
    uint8_t byte;
  };

  void fire_timer();
  void main_loop();
  void update_switches(uint8_t motor);
  void switch_interrupt();
  void trace_line(const std::string& event_json);
  void trace_bytes(const char* event, std::string& pending, const uint8_t* bytes, uint32_t count);

  Ticks now_ = 0;
  Ticks timer_due_ = kNever;
  bool in_interrupt_ = false;
  bool switch_changed_ = false;
  Ticks next_poll_ = 0;
  std::array<Axis, 3> axes_{};
  bool emergency_ = false;
  std::array<std::array<uint16_t, 8>, 3> drv_{};
  std::array<uint16_t, 2> servo_pulse_{};
  std::array<uint16_t, 2> servo_last_pulse_{};
  std::array<std::array<uint8_t, 4>, 2> leds_{};
  std::array<bool, 2> boot_leds_{};
  std::vector<Tone> tones_;
  Ticks byte_ticks_ = 0;          // one byte on the wire; 0: at once
  std::deque<Arrival> line_in_;   // bytes on the wire, not yet received
  std::deque<uint8_t> uart_rx_;   // received, not yet read by the firmware
  Ticks wire_free_at_ = 0;        // when the wire finishes the last queued byte
  std::deque<Arrival> line_out_;  // written by the firmware, still on the wire
  Ticks tx_free_at_ = 0;          // when the transmit wire finishes its last byte
  std::string output_;            // through the wire, not yet taken
  std::string rx_line_, tx_line_;
  bool after_cr_ = false;  // the last line end traced was a CR
  bool record_steps_ = false;
  std::array<std::vector<Ticks>, 3> step_times_;
  std::ostream* trace_ = nullptr;
  std::unique_ptr<Hardware> hardware_;
  proto::ResetCause reset_cause_;
  std::unique_ptr<fw::Controller> controller_;
};

}  // namespace hmc::sim
