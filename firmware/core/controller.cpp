// Controller: lines and their replies, servos, LED strips, queries, settings, switches, timers
// and events (controller.h). Motion lives in controller_motion.cpp. Runs in the main loop except
// on_switch_change().
#include "controller.h"

#include "reply_writer.h"

namespace hmc::fw {
namespace {

using proto::BoardFrameId;
using proto::Reason;

constexpr hal::Ticks ms_to_ticks(uint32_t ms) {
  return static_cast<hal::Ticks>(ms) * (hal::kTicksPerSecond / 1000u);
}

}  // namespace

Controller::Controller(const Board& board, const ControllerOptions& options)
    : board_(board),
      options_(options),
      scheduler_(board.timer, board.pins),
      drivers_{drv8711::Drv8711(board.spi, 1), drv8711::Drv8711(board.spi, 2),
               drv8711::Drv8711(board.spi, 3)},
      parser_(),
      motors_{},
      emergency_(false),
      limits_{},
      servo_release_at_{},
      servo_pulse_{},
      strips_{},
      driver_check_at_(0),
      watchdog_ms_(0),
      watchdog_at_(0),
      watchdog_fired_(false),
      next_mode_(proto::ChecksumMode::kSum),
      boot_led_at_(0),
      boot_led_left_(true),
      tune_(nullptr),
      tune_left_(0),
      tune_next_at_(0),
      self_test_phase_(0),
      accepted_(0),
      refused_(0) {
  for (Motor& mo : motors_) {
    mo.state = MotorState::kIdle;
    mo.microstep = kBootMicrostep;
    mo.toward = kNoEnd;
    for (uint32_t i = 0; i < proto::kSettingCount; ++i) mo.settings[i] = proto::kSettings[i].initial;
  }
}

void Controller::boot(const ResetReport& reset) {
  reset_ = reset;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    const Motor& mo = motors_[index(motor)];
    drv8711::Drv8711& driver = drivers_[index(motor)];
    driver.reset_settings();
    driver.set_current_ma(mo.settings[proto::kSettingCurrent - 1]);
    driver.set_decay_mode(static_cast<drv8711::DecayMode>(mo.settings[proto::kSettingDecay - 1]));
    driver.set_step_mode(kBootMicrostep);
    driver.enable();
    motors_[index(motor)].seen_finished = scheduler_.finished(motor);
  }
  for (uint8_t strip = 1; strip <= proto::kStripCount; ++strip) board_.leds.set_color(strip, 0, 0, 0, 0);
  const hal::Ticks now = board_.timer.now();
  for (uint8_t servo = 1; servo <= proto::kServoCount; ++servo) {
    servo_pulse_[servo - 1] = servo_pulse_us(90);
    board_.servos.set_pulse(servo, servo_pulse_[servo - 1]);
    servo_release_at_[servo - 1] = now + ms_to_ticks(kServoHoldMs);
  }
  play(kBootTune, sizeof(kBootTune) / sizeof(kBootTune[0]));
  boot_led_left_ = true;
  board_.boot_leds.set(true, false);
  boot_led_at_ = now + ms_to_ticks(kBootLedPeriodMs);
  driver_check_at_ = now + ms_to_ticks(kDriverCheckMs);
  const uint32_t booted[] = {proto::kProtocolVersion, proto::kFirmwareVersion};
  send(BoardFrameId::kBooted, booted);
  send_reset(BoardFrameId::kResetEvent);
  check_switches();

  if (options_.self_test && !emergency_) start_self_test();
}

void Controller::poll() {
  scheduler_.fill();
  check_switches();
  for (int byte = board_.serial.read_byte(); byte >= 0; byte = board_.serial.read_byte()) {
    // Every line end feeds the watchdog, a blank line's too: a bare LF is the host's keep-alive,
    // which needs no reply.
    if (watchdog_ms_ != 0 && (byte == '\r' || byte == '\n')) {
      watchdog_at_ = board_.timer.now() + ms_to_ticks(watchdog_ms_);
    }
    if (parser_.feed(static_cast<uint8_t>(byte))) handle_line(parser_.verdict());
  }
  scheduler_.fill();
  check_motions();
  const hal::Ticks now = board_.timer.now();
  check_watchdog(now);
  check_drivers(now);
  run_timers(now);
}

// The host went silent: brake every motor (a stop, with each motor's acceleration), report
// each end as the watchdog's, and disarm, so a later host decides whether to arm it again.
void Controller::check_watchdog(hal::Ticks now) {
  if (watchdog_ms_ == 0 || now < watchdog_at_) return;
  watchdog_ms_ = 0;
  watchdog_fired_ = true;
  abort_self_test();
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    if (!scheduler_.is_running(motor) && mo.state == MotorState::kIdle) continue;
    if (mo.state == MotorState::kHoming) mo.state = MotorState::kMoving;  // no next phase
    mo.halt_cause = proto::kEndWatchdog;
    stop_motor(motor);
  }
}

void Controller::on_switch_change() {
  if (board_.switches.emergency_pressed()) {
    for (Motor& mo : motors_) mo.halt_cause = proto::kEndEmergency;
    scheduler_.halt_all();
    return;
  }
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    const uint8_t end = mo.toward;
    if (end != kNoEnd && board_.switches.limit_pressed(motor, end)) {
      mo.halt_cause = proto::kEndLimit;
      scheduler_.halt(motor);
    }
  }
}

bool Controller::set_acceleration(uint8_t motor, uint32_t steps_per_s2) {
  if (motor < 1 || motor > proto::kMotorCount) return false;
  if (steps_per_s2 > proto::kSettings[proto::kSettingAccel - 1].max) return false;
  motors_[index(motor)].settings[proto::kSettingAccel - 1] = steps_per_s2;
  return true;
}

// ---------------------------------------------------------------------------------------
// Lines

void Controller::handle_line(const Verdict& verdict) {
  check_motions();  // a motion that ended before this line no longer counts as running
  Refusal refusal{verdict.reason, verdict.token};
  uint8_t offset = verdict.offset;
  next_mode_ = parser_.checksum_mode();
  const bool query = verdict.reason == Reason::kOk &&
                     (verdict.command.id == proto::CommandId::kVersion ||
                      verdict.command.id == proto::CommandId::kStatus ||
                      verdict.command.id == proto::CommandId::kGet);
  if (verdict.reason == Reason::kOk) {
    refusal = execute(verdict.command);
    if (refusal.reason != Reason::kOk) offset = parser_.token_offset(refusal.token);
  }
  if (refusal.reason == Reason::kOk) {
    ++accepted_;
    if (!query && options_.replies) write_ack(board_.serial, parser_.checksum_mode());
  } else {
    ++refused_;
    play(kWarningTune, sizeof(kWarningTune) / sizeof(kWarningTune[0]));
    if (options_.replies) {
      write_nak(board_.serial, refusal.reason, refusal.token, offset, parser_.checksum_mode());
    }
  }
  parser_.set_checksum_mode(next_mode_);  // a CRC frame's own reply uses the old mode
}

Controller::Refusal Controller::execute(const Command& command) {
  switch (command.id) {
    case proto::CommandId::kStepper:
      return stepper(command.stepper);
    case proto::CommandId::kServo:
      return servo(command.servo);
    case proto::CommandId::kLed:
      return led(command.led);
    case proto::CommandId::kVersion:
      answer_version();
      return {};
    case proto::CommandId::kStatus:
      answer_status(command.status.unit);
      return {};
    case proto::CommandId::kSet:
      return set(command.setting);
    case proto::CommandId::kGet: {
      const uint32_t values[] = {command.setting.motor, command.setting.setting,
                                 setting(command.setting.motor, command.setting.setting)};
      send(BoardFrameId::kSettingValue, values);
      return {};
    }
    case proto::CommandId::kLimits:
      return limits(command.limits);
    case proto::CommandId::kChecksumMode:
      next_mode_ = static_cast<proto::ChecksumMode>(command.checksum_mode.mode);
      return {};
    case proto::CommandId::kWatchdog:
      watchdog_ms_ = command.watchdog.timeout_ms;
      watchdog_at_ = board_.timer.now() + ms_to_ticks(watchdog_ms_);
      if (watchdog_ms_ != 0) watchdog_fired_ = false;
      return {};
    case proto::CommandId::kSetPosition:
      return set_position(command.position);
  }
  return {Reason::kUnknownCommand, proto::kTokenName};
}

Controller::Refusal Controller::servo(const ServoCommand& command) {
  if (emergency_) return {Reason::kEmergencyStop, proto::kTokenName};
  if (options_.legacy && any_moving()) return {Reason::kBusy, proto::kTokenName};
  servo_pulse_[command.servo - 1] = servo_pulse_us(command.angle);
  board_.servos.set_pulse(command.servo, servo_pulse_[command.servo - 1]);
  servo_release_at_[command.servo - 1] = board_.timer.now() + ms_to_ticks(kServoHoldMs);
  return {};
}

Controller::Refusal Controller::led(const LedCommand& command) {
  if (options_.legacy && any_moving()) return {Reason::kBusy, proto::kTokenName};
  uint8_t* colour = strips_[command.strip - 1];
  colour[0] = command.r, colour[1] = command.g, colour[2] = command.b, colour[3] = command.w;
  board_.leds.set_color(command.strip, command.r, command.g, command.b, command.w);
  return {};
}

// ---------------------------------------------------------------------------------------
// Settings and queries

Controller::Refusal Controller::set(const SettingCommand& command) {
  Motor& mo = motors_[index(command.motor)];
  drv8711::Drv8711& driver = drivers_[index(command.motor)];
  switch (command.setting) {
    case proto::kSettingCurrent:
      driver.set_current_ma(command.value);
      break;
    case proto::kSettingDecay:
      driver.set_decay_mode(static_cast<drv8711::DecayMode>(command.value));
      break;
    default:
      break;
  }
  mo.settings[command.setting - 1] = command.value;
  return {};
}

Controller::Refusal Controller::limits(const LimitsCommand& command) {
  Motor& mo = motors_[index(command.motor)];
  mo.soft_low = command.low_sign != 0 ? -static_cast<int64_t>(command.low) : command.low;
  mo.soft_high = command.high_sign != 0 ? -static_cast<int64_t>(command.high) : command.high;
  mo.soft_limits = mo.soft_low < mo.soft_high;
  return {};
}

// POS: the resting motor is where the host says (its zero, or a given value), and its position
// means something from now on, as after homing: STA reports it homed. A moving motor keeps
// counting: refused (motors_running), as the scheduler sets positions only at rest.
Controller::Refusal Controller::set_position(const PositionCommand& command) {
  Motor& mo = motors_[index(command.motor)];
  if (mo.state != MotorState::kIdle) return {Reason::kMotorsRunning, proto::kTokenFirstValue};
  const int32_t position = command.sign != 0 ? -static_cast<int32_t>(command.position) : static_cast<int32_t>(command.position);
  if (!scheduler_.set_position(command.motor, position)) return {Reason::kMotorsRunning, proto::kTokenFirstValue};
  mo.homed = true;
  return {};
}

void Controller::answer_version() {
  const uint32_t values[] = {proto::kProtocolVersion,
                             proto::kFirmwareVersion,
                             options_.legacy ? 1u : 0u,
                             proto::kLineMax,
                             kMaxStepRate,
                             proto::kMotorCount * 100 + proto::kServoCount * 10 + proto::kStripCount,
                             (proto::motor_has_switches(1) ? 1u : 0u) | (proto::motor_has_switches(2) ? 2u : 0u) |
                                 (proto::motor_has_switches(3) ? 4u : 0u),
                             static_cast<uint32_t>(parser_.checksum_mode()),
                             proto::kMaxRampingStepRate};
  static_assert(sizeof(values) / sizeof(values[0]) == proto::board_frame_spec(BoardFrameId::kVersion).value_count,
                "one value per VER field");
  send(BoardFrameId::kVersion, values);
}

void Controller::send_reset(BoardFrameId id) {
  // Clamped to the fields' ranges: a record read back from RAM after a fault is only as good
  // as the RAM was.
  auto exception_number = [](uint32_t n) { return n <= proto::kMaxException ? n : 0u; };
  const uint32_t cause = static_cast<uint32_t>(reset_.cause);
  const uint32_t values[] = {cause < proto::kResetCauseCount ? cause : 0u, exception_number(reset_.exception),
                             reset_.pc & proto::kIntMax, reset_.lr & proto::kIntMax,
                             exception_number(reset_.context)};
  send(id, values);
}

void Controller::answer_status(uint8_t unit) {
  if (unit == proto::kUnitWatchdog) {
    const uint32_t values[] = {watchdog_ms_, watchdog_fired_ ? 1u : 0u};
    send(BoardFrameId::kWatchdogStatus, values);
    return;
  }
  if (unit == proto::kUnitReset) {
    send_reset(BoardFrameId::kResetStatus);
    return;
  }
  if (unit >= proto::kUnitFirstStrip) {
    const uint8_t* c = strips_[unit - proto::kUnitFirstStrip];
    const uint32_t values[] = {static_cast<uint32_t>(unit - proto::kUnitFirstStrip + 1), c[0], c[1], c[2], c[3]};
    send(BoardFrameId::kStripStatus, values);
    return;
  }
  if (unit == proto::kUnitBoard) {
    uint32_t mask = 0;
    for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
      for (uint8_t end = 0; end < 2; ++end) {
        if (limits_[index(motor)][end]) mask |= 1u << (2u * index(motor) + end);
      }
    }
    const uint32_t values[] = {emergency_ ? 1u : 0u, mask, servo_pulse_[0], servo_pulse_[1]};
    send(BoardFrameId::kBoardStatus, values);
    return;
  }
  const Motor& mo = motors_[index(unit)];
  int32_t target = 0;
  const bool endless = !scheduler_.target(unit, target);
  uint32_t log2_microstep = 0;
  while ((1u << log2_microstep) < mo.microstep) ++log2_microstep;
  const uint32_t flags = (mo.homed ? 1u : 0u) | (limits_[index(unit)][0] ? 2u : 0u) |
                         (limits_[index(unit)][1] ? 4u : 0u) | (endless ? 8u : 0u) | (log2_microstep << 4);
  uint32_t values[8] = {unit, static_cast<uint32_t>(mo.state)};
  put_signed(values + 2, scheduler_.position(unit));
  put_signed(values + 4, endless ? scheduler_.position(unit) : target);
  values[6] = scheduler_.rate(unit);
  values[7] = flags;
  send(BoardFrameId::kMotorStatus, values);
}

// ---------------------------------------------------------------------------------------
// Events

void Controller::send(BoardFrameId id, const uint32_t* values) {
  if (options_.replies) write_frame(board_.serial, id, values, parser_.checksum_mode());
}

void Controller::send_motion_ended(uint8_t motor, uint32_t how) {
  uint32_t values[4] = {motor, how};
  put_signed(values + 2, scheduler_.position(motor));
  send(BoardFrameId::kMotionEnded, values);
}

void Controller::send_homing_ended(uint8_t motor, bool homed) {
  uint32_t values[4] = {motor, homed ? 1u : 0u};
  put_signed(values + 2, scheduler_.position(motor));
  send(BoardFrameId::kHomingEnded, values);
}

// ---------------------------------------------------------------------------------------
// Switches, drivers and timers

void Controller::check_switches() {
  const bool emergency = board_.switches.emergency_pressed();
  if (emergency != emergency_) {
    const uint32_t pressed[] = {emergency ? 1u : 0u};
    send(BoardFrameId::kEmergencyChanged, pressed);
  }
  if (emergency && !emergency_) {
    for (Motor& mo : motors_) mo.halt_cause = proto::kEndEmergency;
    scheduler_.halt_all();
    self_test_phase_ = 0;
    for (Motor& mo : motors_) {
      if (mo.state == MotorState::kChanging || mo.state == MotorState::kSelfTest) {
        mo.state = MotorState::kMoving;  // the halt ends it; nothing waits
      }
    }
  }
  emergency_ = emergency;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    if (!proto::motor_has_switches(motor)) continue;
    Motor& mo = motors_[index(motor)];
    for (uint8_t end = 0; end < 2; ++end) {
      const bool pressed = board_.switches.limit_pressed(motor, end);
      if (pressed != limits_[index(motor)][end]) {
        const uint32_t values[] = {motor, end, pressed ? 1u : 0u};
        send(BoardFrameId::kLimitChanged, values);
      }
      limits_[index(motor)][end] = pressed;
    }
    // The interrupt halts at the edge; this covers a switch found pressed by polling alone.
    const uint8_t toward = mo.toward;
    if (toward != kNoEnd && limits_[index(motor)][toward] && scheduler_.is_running(motor)) {
      mo.halt_cause = proto::kEndLimit;
      scheduler_.halt(motor);
    }
  }
}

// Reads each driver's STATUS; a fault not yet reported is sent once (EVF) and cleared, so a
// fault still present latches again and is reported again after it went away.
void Controller::check_drivers(hal::Ticks now) {
  if (now < driver_check_at_) return;
  driver_check_at_ = now + ms_to_ticks(kDriverCheckMs);
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    const uint8_t bits = static_cast<uint8_t>(drivers_[index(motor)].read_register(drv8711::Register::kStatus));
    if (bits != 0 && bits != mo.fault_reported) {
      const uint32_t values[] = {motor, bits};
      send(BoardFrameId::kDriverFault, values);
      drivers_[index(motor)].clear_status();
    }
    mo.fault_reported = bits;
  }
}

void Controller::run_timers(hal::Ticks now) {
  for (uint8_t servo = 1; servo <= proto::kServoCount; ++servo) {
    hal::Ticks& at = servo_release_at_[servo - 1];
    if (at != 0 && now >= at) {
      board_.servos.release(servo);
      servo_pulse_[servo - 1] = 0;
      at = 0;
    }
  }
  if (now >= boot_led_at_) {
    boot_led_left_ = !boot_led_left_;
    board_.boot_leds.set(boot_led_left_, !boot_led_left_);
    boot_led_at_ += ms_to_ticks(kBootLedPeriodMs);
    if (boot_led_at_ <= now) boot_led_at_ = now + ms_to_ticks(kBootLedPeriodMs);
  }
  if (tune_left_ != 0 && now >= tune_next_at_) next_note(now);
}

void Controller::play(const Note* tune, uint8_t count) {
  tune_ = tune;
  tune_left_ = count;
  next_note(board_.timer.now());
}

void Controller::next_note(hal::Ticks now) {
  board_.buzzer.tone(tune_->hz, tune_->ms);
  tune_next_at_ = now + ms_to_ticks(tune_->ms);
  ++tune_;
  --tune_left_;
}

}  // namespace hmc::fw
