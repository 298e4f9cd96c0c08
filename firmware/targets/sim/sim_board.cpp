// SimBoard: the simulated hardware behind the HAL and the event loop on the virtual clock.
#include "sim_board.h"

#include <algorithm>
#include <cstdio>

#include "core/drv8711.h"

namespace hmc::sim {
namespace {

namespace drv = fw::drv8711;

const char* flag(bool b) { return b ? "true" : "false"; }

// A JSON string literal for raw line bytes: printable ASCII as is, the rest escaped.
std::string json_string(const std::string& bytes) {
  std::string out = "\"";
  for (const char c : bytes) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u >= 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

// Every HAL interface, over the board's state. The core sees only the interfaces.
class SimBoard::Hardware final : public hal::StepTimer,
                                 public hal::StepPins,
                                 public hal::SpiBus,
                                 public hal::ServoPwm,
                                 public hal::LedStrips,
                                 public hal::Switches,
                                 public hal::Buzzer,
                                 public hal::BootLeds,
                                 public hal::SerialPort {
 public:
  explicit Hardware(SimBoard& board) : b_(board) {}

  Ticks now() const override { return b_.now_; }
  void schedule(Ticks when) override {
    b_.timer_due_ = when;
    // A compare already due pends the interrupt: it preempts the main loop at once.
    if (!b_.in_interrupt_ && when <= b_.now_) b_.fire_timer();
  }

  void set_dir(uint8_t motor, bool reverse) override {
    b_.axes_[motor - 1].reverse = reverse;
    b_.trace_line("\"ev\":\"dir\",\"motor\":" + std::to_string(motor) + ",\"reverse\":" + flag(reverse));
  }
  void set_step(uint8_t motor, bool high) override {
    Axis& axis = b_.axes_[motor - 1];
    const bool rising = high && !axis.step_high;
    axis.step_high = high;
    if (!rising) return;
    ++axis.steps;
    if (b_.driver_enabled(motor)) {
      const auto units = static_cast<int32_t>(256u / b_.driver_microstep(motor));
      axis.position += axis.reverse ? -units : units;
    }
    if (b_.record_steps_) b_.step_times_[motor - 1].push_back(b_.now_);
    if (b_.trace_ != nullptr) {  // the hot path: no strings built for a trace nobody reads
      b_.trace_line("\"ev\":\"step\",\"motor\":" + std::to_string(motor) + ",\"pos\":" +
                    std::to_string(axis.position));
    }
    b_.update_switches(motor);
  }

  uint16_t transfer16(uint8_t chip, uint16_t word) override {
    if (chip < 1 || chip > 3) return 0;
    auto& regs = b_.drv_[chip - 1];
    const auto address = static_cast<uint8_t>((word >> drv::kAddressShift) & 0x7u);
    if ((word & drv::kReadBit) != 0) return regs[address];
    const auto data = static_cast<uint16_t>(word & drv::kDataMask);
    if (address == static_cast<uint8_t>(drv::Register::kStatus)) {
      regs[address] = static_cast<uint16_t>(regs[address] & data);  // writing 0 clears a bit
      return 0;
    }
    const uint16_t before = regs[address];
    regs[address] = data;
    if (address == static_cast<uint8_t>(drv::Register::kCtrl) && before != data) {
      b_.trace_line("\"ev\":\"driver\",\"motor\":" + std::to_string(chip) + ",\"enabled\":" +
                    flag(b_.driver_enabled(chip)) + ",\"microstep\":" +
                    std::to_string(b_.driver_microstep(chip)));
    }
    return 0;
  }

  void set_pulse(uint8_t servo, uint16_t pulse_us) override {
    b_.servo_pulse_[servo - 1] = pulse_us;
    b_.servo_last_pulse_[servo - 1] = pulse_us;
    b_.trace_line("\"ev\":\"servo\",\"servo\":" + std::to_string(servo) + ",\"pulse_us\":" +
                  std::to_string(pulse_us));
  }
  void release(uint8_t servo) override {
    b_.servo_pulse_[servo - 1] = 0;
    b_.trace_line("\"ev\":\"servo\",\"servo\":" + std::to_string(servo) + ",\"released\":true");
  }

  void set_color(uint8_t strip, uint8_t r, uint8_t g, uint8_t b, uint8_t w) override {
    b_.leds_[strip - 1] = {r, g, b, w};
    b_.trace_line("\"ev\":\"led\",\"strip\":" + std::to_string(strip) + ",\"r\":" + std::to_string(r) +
                  ",\"g\":" + std::to_string(g) + ",\"b\":" + std::to_string(b) +
                  ",\"w\":" + std::to_string(w));
  }

  bool limit_pressed(uint8_t motor, uint8_t end) const override {
    return b_.limit_pressed(motor, end);
  }
  bool emergency_pressed() const override { return b_.emergency_; }

  void tone(uint16_t hz, uint16_t ms) override {
    b_.tones_.push_back({b_.now_, hz, ms});
    b_.trace_line("\"ev\":\"tone\",\"hz\":" + std::to_string(hz) + ",\"ms\":" + std::to_string(ms));
  }

  void set(bool left_on, bool right_on) override {
    b_.boot_leds_ = {left_on, right_on};
    b_.trace_line(std::string("\"ev\":\"boot_leds\",\"left\":") + flag(left_on) +
                  ",\"right\":" + flag(right_on));
  }

  int read_byte() override {
    if (b_.uart_rx_.empty()) return -1;
    const uint8_t byte = b_.uart_rx_.front();
    b_.uart_rx_.pop_front();
    return byte;
  }
  void write(const uint8_t* bytes, uint32_t count) override {
    if (b_.byte_ticks_ == 0) {
      b_.output_.append(reinterpret_cast<const char*>(bytes), count);
    } else {
      for (uint32_t i = 0; i < count; ++i) {
        b_.tx_free_at_ = std::max(b_.tx_free_at_, b_.now_) + b_.byte_ticks_;
        b_.line_out_.push_back({b_.tx_free_at_, bytes[i]});
      }
    }
    b_.trace_bytes("tx", b_.tx_line_, bytes, count);
  }

 private:
  SimBoard& b_;
};

const char* state_name(fw::MotorState state) {
  switch (state) {
    case fw::MotorState::kIdle: return "idle";
    case fw::MotorState::kMoving: return "moving";
    case fw::MotorState::kHoming: return "homing";
    case fw::MotorState::kChanging: return "changing";
    case fw::MotorState::kSelfTest: return "self_test";
  }
  return "unknown";
}

SimBoard::SimBoard(const SimConfig& config) : hardware_(new Hardware(*this)), reset_cause_(config.reset_cause) {
  if (config.baud != 0) {
    // 10 bits per byte (start, 8 data, stop), rounded up to the tick.
    byte_ticks_ = (uint64_t{10} * hal::kTicksPerSecond + config.baud - 1) / config.baud;
  }
  for (uint8_t i = 0; i < 3; ++i) {
    axes_[i].config = config.axes[i];
    axes_[i].position = config.axes[i].start;
    // Power-on values: the driver's reset values, STATUS clear.
    for (uint8_t r = 0; r < drv::kSettingRegisterCount; ++r) drv_[i][r] = drv::kResetValues[r];
  }
  for (uint8_t motor = 1; motor <= 3; ++motor) {
    Axis& axis = axes_[motor - 1];
    for (uint8_t end = 0; end < 2; ++end) axis.pressed[end] = limit_pressed(motor, end);
  }
  Hardware& hw = *hardware_;
  const fw::Board board{hw, hw, hw, hw, hw, hw, hw, hw, hw};
  controller_ = std::make_unique<fw::Controller>(board, config.options);
  for (uint8_t motor = 1; motor <= 3; ++motor) {
    controller_->set_acceleration(motor, config.accel[motor - 1]);
  }
}

SimBoard::~SimBoard() = default;

void SimBoard::boot() {
  fw::ResetReport reset;
  reset.cause = reset_cause_;
  controller_->boot(reset);
  next_poll_ = now_;
  main_loop();
}

Ticks SimBoard::next_event() const {
  Ticks t = std::max(next_poll_, now_);
  if (timer_due_ < t) t = std::max(timer_due_, now_);
  if (!line_in_.empty() && line_in_.front().at < t) t = std::max(line_in_.front().at, now_);
  if (!line_out_.empty() && line_out_.front().at < t) t = std::max(line_out_.front().at, now_);
  return t;
}

void SimBoard::run_until(Ticks t) {
  while (true) {
    const Ticks next = next_event();
    if (next > t) break;
    now_ = next;
    if (timer_due_ <= now_) {
      fire_timer();
    } else if (!line_in_.empty() && line_in_.front().at <= now_) {
      while (!line_in_.empty() && line_in_.front().at <= now_) {
        const uint8_t byte = line_in_.front().byte;
        line_in_.pop_front();
        uart_rx_.push_back(byte);
        trace_bytes("rx", rx_line_, &byte, 1);
      }
      main_loop();
    } else if (!line_out_.empty() && line_out_.front().at <= now_) {
      // Through the wire: the host's to take. The firmware does not see it, so no main loop.
      while (!line_out_.empty() && line_out_.front().at <= now_) {
        output_ += static_cast<char>(line_out_.front().byte);
        line_out_.pop_front();
      }
    } else {
      main_loop();
    }
  }
  if (t > now_) now_ = t;
}

bool SimBoard::busy() const {
  if (receiving() || transmitting()) return true;
  for (uint8_t motor = 1; motor <= 3; ++motor) {
    if (controller_->scheduler().is_running(motor)) return true;
    if (controller_->state(motor) != fw::MotorState::kIdle) return true;
  }
  return false;
}

void SimBoard::send(const std::string& bytes) {
  Ticks at = std::max(now_, wire_free_at_);
  for (const char c : bytes) {
    at += byte_ticks_;
    line_in_.push_back({at, static_cast<uint8_t>(c)});
  }
  wire_free_at_ = at;
}

std::string SimBoard::take_output() {
  std::string out;
  out.swap(output_);
  return out;
}

Ticks SimBoard::next_output() const {
  if (!output_.empty()) return now_;
  return line_out_.empty() ? kNever : line_out_.front().at;
}

std::string SimBoard::take_written() {
  std::string out = take_output();
  for (const Arrival& byte : line_out_) out += static_cast<char>(byte.byte);
  line_out_.clear();
  return out;
}

void SimBoard::drop_output() {
  output_.clear();
  line_out_.clear();
}

void SimBoard::force_limit(uint8_t motor, uint8_t end, Force force) {
  if (motor < 1 || motor > 3 || end > 1) return;
  axes_[motor - 1].force[end] = force;
  update_switches(motor);
  if (switch_changed_) switch_interrupt();
  main_loop();
}

void SimBoard::set_emergency(bool pressed) {
  if (pressed == emergency_) return;
  emergency_ = pressed;
  trace_line(std::string("\"ev\":\"emergency\",\"pressed\":") + flag(pressed));
  switch_changed_ = true;
  switch_interrupt();
  main_loop();
}

void SimBoard::set_driver_fault(uint8_t motor, uint8_t status_bits) {
  if (motor < 1 || motor > 3) return;
  uint16_t& status = drv_[motor - 1][static_cast<uint8_t>(drv::Register::kStatus)];
  status = static_cast<uint16_t>(status | status_bits);
  trace_line("\"ev\":\"fault\",\"motor\":" + std::to_string(motor) + ",\"status\":" + std::to_string(status));
}

int32_t SimBoard::axis_position(uint8_t motor) const { return axes_[motor - 1].position; }
uint32_t SimBoard::steps(uint8_t motor) const { return axes_[motor - 1].steps; }

bool SimBoard::limit_pressed(uint8_t motor, uint8_t end) const {
  if (motor < 1 || motor > 3 || end > 1) return false;
  const Axis& axis = axes_[motor - 1];
  if (axis.force[end] != Force::kNone) return axis.force[end] == Force::kPressed;
  if (!axis.config.has_switches) return false;
  return end == 0 ? axis.position <= axis.config.low_switch : axis.position >= axis.config.high_switch;
}

uint16_t SimBoard::servo_pulse(uint8_t servo) const { return servo_pulse_[servo - 1]; }
uint16_t SimBoard::servo_last_pulse(uint8_t servo) const { return servo_last_pulse_[servo - 1]; }
std::array<uint8_t, 4> SimBoard::led(uint8_t strip) const { return leds_[strip - 1]; }

uint16_t SimBoard::driver_register(uint8_t motor, uint8_t address) const {
  return drv_[motor - 1][address & 7u];
}
uint32_t SimBoard::driver_microstep(uint8_t motor) const {
  return 1u << drv::ctrl::kMode.get(drv_[motor - 1][0]);
}
bool SimBoard::driver_enabled(uint8_t motor) const {
  return drv::ctrl::kEnable.get(drv_[motor - 1][0]) != 0;
}

void SimBoard::clear_step_times() {
  for (auto& times : step_times_) times.clear();
}

// The step timer's interrupt, then the switch interrupt it may have caused (lower priority).
void SimBoard::fire_timer() {
  timer_due_ = kNever;
  in_interrupt_ = true;
  controller_->on_step_timer();
  in_interrupt_ = false;
  if (switch_changed_) {
    switch_interrupt();
    main_loop();
  }
}

void SimBoard::main_loop() {
  controller_->poll();
  next_poll_ = now_ + kPollTicks;
}

void SimBoard::update_switches(uint8_t motor) {
  Axis& axis = axes_[motor - 1];
  for (uint8_t end = 0; end < 2; ++end) {
    const bool pressed = limit_pressed(motor, end);
    if (pressed == axis.pressed[end]) continue;
    axis.pressed[end] = pressed;
    switch_changed_ = true;
    trace_line("\"ev\":\"switch\",\"motor\":" + std::to_string(motor) + ",\"end\":" +
               std::to_string(end) + ",\"pressed\":" + flag(pressed));
  }
}

void SimBoard::switch_interrupt() {
  switch_changed_ = false;
  controller_->on_switch_change();
}

void SimBoard::trace_line(const std::string& event_json) {
  if (trace_ == nullptr) return;
  *trace_ << "{\"t\":" << now_ << ',' << event_json << "}\n";
}

// Collects bytes into lines for the trace; a line is written at its LF or CR.
void SimBoard::trace_bytes(const char* event, std::string& pending, const uint8_t* bytes,
                           uint32_t count) {
  if (trace_ == nullptr) return;
  for (uint32_t i = 0; i < count; ++i) {
    const char c = static_cast<char>(bytes[i]);
    if (c != '\n' && c != '\r') {
      if (pending.size() < 4096) pending += c;
      continue;
    }
    if (!pending.empty()) {
      trace_line(std::string("\"ev\":\"") + event + "\",\"line\":" + json_string(pending));
    } else if (c == '\n' && !after_cr_) {
      // A blank line (not the LF of a CRLF): a host's keep-alive for the link watchdog.
      trace_line(std::string("\"ev\":\"") + event + "_blank\"");
    }
    after_cr_ = c == '\r';
    pending.clear();
  }
}

}  // namespace hmc::sim
