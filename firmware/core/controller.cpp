// Controller: what accepted frames do, the rules that refuse them, switches, timers and the
// self-test (controller.h). Runs in the main loop except on_switch_change().
#include "controller.h"

#include "reply_writer.h"

namespace hmc::fw {
namespace {

using proto::Reason;

constexpr hal::Ticks ms_to_ticks(uint32_t ms) {
  return static_cast<hal::Ticks>(ms) * (hal::kTicksPerSecond / 1000u);
}

// The token a rule refusal concerns (docs/protocol.md, "Replies").
constexpr uint8_t kTokenDir = proto::kTokenFirstValue + 1;
constexpr uint8_t kTokenDelay = proto::kTokenFirstValue + 4;

// Ticks per step for `delay_us`, or 0 when the timer cannot produce it.
uint32_t interval_for(uint32_t delay_us) {
  const uint64_t ticks = static_cast<uint64_t>(delay_us) * hal::kTicksPerMicrosecond;
  if (ticks < kMinIntervalTicks || ticks > 0xFFFFFFFFu) return 0;
  return static_cast<uint32_t>(ticks);
}

uint32_t rate_for(uint32_t delay_us) { return (1000000u + delay_us - 1u) / delay_us; }

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
  }
}

void Controller::boot() {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    drv8711::Drv8711& driver = drivers_[index(motor)];
    driver.reset_settings();
    driver.set_current_ma(kBootCurrentMa);
    driver.set_decay_mode(drv8711::DecayMode::kAutoMixed);
    driver.set_step_mode(kBootMicrostep);
    driver.enable();
    motors_[index(motor)].seen_finished = scheduler_.finished(motor);
  }
  for (uint8_t strip = 1; strip <= proto::kStripCount; ++strip) board_.leds.set_color(strip, 0, 0, 0, 0);
  const hal::Ticks now = board_.timer.now();
  for (uint8_t servo = 1; servo <= proto::kServoCount; ++servo) {
    board_.servos.set_pulse(servo, servo_pulse_us(90));
    servo_release_at_[servo - 1] = now + ms_to_ticks(kServoHoldMs);
  }
  play(kBootTune, sizeof(kBootTune) / sizeof(kBootTune[0]));
  boot_led_left_ = true;
  board_.boot_leds.set(true, false);
  boot_led_at_ = now + ms_to_ticks(kBootLedPeriodMs);
  check_switches();

  if (!options_.self_test || emergency_) return;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    const MoveSpec forward{false, static_cast<uint16_t>(kBootMicrostep), kSelfTestSteps,
                           interval_for(kSelfTestDelayUs), 0};
    if (start_move(motor, forward, rate_for(kSelfTestDelayUs), MotorState::kSelfTest) ==
        Reason::kOk) {
      self_test_phase_ = 1;
    }
  }
}

void Controller::poll() {
  check_switches();
  for (int byte = board_.serial.read_byte(); byte >= 0; byte = board_.serial.read_byte()) {
    if (parser_.feed(static_cast<uint8_t>(byte))) handle_line(parser_.verdict());
  }
  check_motions();
  run_timers(board_.timer.now());
}

void Controller::on_switch_change() {
  if (board_.switches.emergency_pressed()) {
    scheduler_.halt_all();
    return;
  }
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    const uint8_t end = motors_[index(motor)].toward;
    if (end != kNoEnd && board_.switches.limit_pressed(motor, end)) scheduler_.halt(motor);
  }
}

bool Controller::set_acceleration(uint8_t motor, uint32_t steps_per_s2) {
  if (motor < 1 || motor > proto::kMotorCount) return false;
  motors_[index(motor)].accel = steps_per_s2;
  return true;
}

// ---------------------------------------------------------------------------------------
// Lines

void Controller::handle_line(const Verdict& verdict) {
  check_motions();  // a motion that ended before this line no longer counts as running
  Refusal refusal{verdict.reason, verdict.token};
  uint8_t offset = verdict.offset;
  if (verdict.reason == Reason::kOk) {
    refusal = execute(verdict.command);
    if (refusal.reason != Reason::kOk) offset = parser_.token_offset(refusal.token);
  }
  if (refusal.reason == Reason::kOk) {
    ++accepted_;
    if (options_.replies) write_ack(board_.serial);
    return;
  }
  ++refused_;
  play(kWarningTune, sizeof(kWarningTune) / sizeof(kWarningTune[0]));
  if (options_.replies) write_nak(board_.serial, refusal.reason, refusal.token, offset);
}

Controller::Refusal Controller::execute(const Command& command) {
  switch (command.id) {
    case proto::CommandId::kStepper:
      return stepper(command.stepper);
    case proto::CommandId::kServo:
      return servo(command.servo);
    case proto::CommandId::kLed:
      return led(command.led);
  }
  return {Reason::kUnknownCommand, proto::kTokenName};
}

Controller::Refusal Controller::stepper(const StepperCommand& command) {
  const uint8_t motor = command.motor;
  if (command.dir == proto::kActionStop) {
    abort_self_test();
    stop_motor(motor);
    return {};
  }
  if (emergency_) return {Reason::kEmergencyStop, proto::kTokenName};
  abort_self_test();
  if (command.dir == proto::kActionHome) return home(command);

  const bool reverse = command.dir == proto::kActionReverse;
  const uint8_t end = reverse ? 0 : 1;
  if (proto::motor_has_switches(motor) && limits_[index(motor)][end]) {
    return {Reason::kLimitPressed, kTokenDir};
  }
  const uint32_t interval = interval_for(command.delay_us);
  if (interval == 0) return {Reason::kRateLimit, kTokenDelay};
  const MoveSpec move{reverse, static_cast<uint16_t>(command.microstep), command.steps, interval,
                      motors_[index(motor)].accel};
  return {start_move(motor, move, rate_for(command.delay_us), MotorState::kMoving), kTokenDelay};
}

Controller::Refusal Controller::home(const StepperCommand& command) {
  const uint8_t motor = command.motor;
  if (any_moving()) return {Reason::kMotorsRunning, kTokenDir};
  Motor& mo = motors_[index(motor)];
  if (limits_[index(motor)][0]) {  // already on the home switch
    scheduler_.set_position(motor, 0);
    mo.homed = true;
    return {};
  }
  const uint32_t delay_us = command.delay_us != 0 ? command.delay_us : kHomingDelayUs;
  const uint32_t interval = interval_for(delay_us);
  if (interval == 0) return {Reason::kRateLimit, kTokenDelay};
  const uint32_t microstep = command.microstep != 0 ? command.microstep : mo.microstep;
  // Homing seeks at constant rate: the switch halts it where it closed.
  const MoveSpec seek{true, static_cast<uint16_t>(microstep), command.steps, interval, 0};
  mo.homed = false;
  return {start_move(motor, seek, rate_for(delay_us), MotorState::kHoming), kTokenDelay};
}

Controller::Refusal Controller::servo(const ServoCommand& command) {
  if (emergency_) return {Reason::kEmergencyStop, proto::kTokenName};
  if (options_.legacy && any_moving()) return {Reason::kBusy, proto::kTokenName};
  board_.servos.set_pulse(command.servo, servo_pulse_us(command.angle));
  servo_release_at_[command.servo - 1] = board_.timer.now() + ms_to_ticks(kServoHoldMs);
  return {};
}

Controller::Refusal Controller::led(const LedCommand& command) {
  if (options_.legacy && any_moving()) return {Reason::kBusy, proto::kTokenName};
  board_.leds.set_color(command.strip, command.r, command.g, command.b, command.w);
  return {};
}

// ---------------------------------------------------------------------------------------
// Motion

// Starts `move`, or, when it needs the motor at rest first (another microstep or the other
// direction), stops the motor and keeps the move until it rests (check_motions).
Reason Controller::start_move(uint8_t motor, const MoveSpec& move, uint32_t rate,
                              MotorState state) {
  Motor& mo = motors_[index(motor)];
  if (!within_budget(motor, rate, move.accel)) return Reason::kRateLimit;
  const bool running = scheduler_.is_running(motor);
  if (running && (move.microstep != mo.microstep || move.reverse != mo.reverse)) {
    scheduler_.stop(motor);
    mo.pending = move;
    mo.pending_rate = rate;
    mo.pending_state = state;
    mo.state = MotorState::kChanging;
    return Reason::kOk;
  }
  if (!running && move.microstep != mo.microstep) {
    drivers_[index(motor)].set_step_mode(move.microstep);
    mo.microstep = move.microstep;
  }
  // Set before the move starts, so the switch interrupt can halt it from its first step.
  mo.toward = proto::motor_has_switches(motor) ? (move.reverse ? 0 : 1) : kNoEnd;
  if (scheduler_.start(motor, move) != StepStatus::kOk) {
    if (!running) mo.toward = kNoEnd;
    return Reason::kRateLimit;  // the plan's limits: interval, acceleration, ramp length
  }
  mo.reverse = move.reverse;
  mo.rate = rate;
  mo.state = state;
  return Reason::kOk;
}

bool Controller::within_budget(uint8_t motor, uint32_t rate, uint32_t accel) const {
  uint32_t sum = rate;
  bool ramping = accel != 0;
  for (uint8_t other = 1; other <= proto::kMotorCount; ++other) {
    const Motor& mo = motors_[index(other)];
    if (other == motor || !scheduler_.is_running(other)) continue;
    const bool changing = mo.state == MotorState::kChanging;
    const uint32_t other_rate = changing && mo.pending_rate > mo.rate ? mo.pending_rate : mo.rate;
    sum += other_rate;
    ramping = ramping || mo.accel != 0;
  }
  return sum <= (ramping ? kMaxRampingStepRate : kMaxStepRate);
}

bool Controller::any_moving() const {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    if (scheduler_.is_running(motor)) return true;
  }
  return false;
}

void Controller::stop_motor(uint8_t motor) {
  Motor& mo = motors_[index(motor)];
  if (mo.state == MotorState::kChanging) mo.state = MotorState::kMoving;  // drop the waiting move
  scheduler_.stop(motor);
}

void Controller::abort_self_test() {
  if (self_test_phase_ == 0) return;
  self_test_phase_ = 0;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    if (mo.state != MotorState::kSelfTest) continue;
    scheduler_.halt(motor);
    mo.state = MotorState::kMoving;  // ends like any move (check_motions)
  }
}

// Bookkeeping for motions that ended: homing completes, a waiting move starts.
void Controller::check_motions() {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    const uint32_t finished = scheduler_.finished(motor);
    if (finished == mo.seen_finished) continue;
    mo.seen_finished = finished;
    if (scheduler_.is_running(motor)) continue;  // an earlier motion; the one running is newer
    switch (mo.state) {
      case MotorState::kHoming:
        if (limits_[index(motor)][0] || board_.switches.limit_pressed(motor, 0)) {
          scheduler_.set_position(motor, 0);
          mo.homed = true;
        }
        break;
      case MotorState::kChanging: {
        mo.state = MotorState::kIdle;
        mo.rate = 0;
        mo.toward = kNoEnd;
        const uint8_t end = mo.pending.reverse ? 0 : 1;
        const bool blocked = proto::motor_has_switches(motor) && limits_[index(motor)][end];
        if (!emergency_ && !blocked) start_move(motor, mo.pending, mo.pending_rate, mo.pending_state);
        continue;
      }
      case MotorState::kSelfTest:
        continue;  // advance_self_test() decides
      default:
        break;
    }
    mo.state = MotorState::kIdle;
    mo.rate = 0;
    mo.toward = kNoEnd;
  }
  advance_self_test();
}

// Phase 1 runs every motor forward; when all rest, phase 2 brings each back as far as it went.
void Controller::advance_self_test() {
  if (self_test_phase_ == 0) return;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    if (motors_[index(motor)].state == MotorState::kSelfTest && scheduler_.is_running(motor)) return;
  }
  const bool back = self_test_phase_ == 1;
  self_test_phase_ = 0;
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    if (mo.state != MotorState::kSelfTest) continue;
    mo.state = MotorState::kIdle;
    mo.rate = 0;
    mo.toward = kNoEnd;
    const uint32_t steps = scheduler_.steps_done(motor);
    if (!back || steps == 0 || emergency_ || limits_[index(motor)][0]) continue;
    const MoveSpec reverse{true, static_cast<uint16_t>(kBootMicrostep), steps,
                           interval_for(kSelfTestDelayUs), 0};
    if (start_move(motor, reverse, rate_for(kSelfTestDelayUs), MotorState::kSelfTest) ==
        Reason::kOk) {
      self_test_phase_ = 2;
    }
  }
}

// ---------------------------------------------------------------------------------------
// Switches and timers

void Controller::check_switches() {
  const bool emergency = board_.switches.emergency_pressed();
  if (emergency && !emergency_) {
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
    for (uint8_t end = 0; end < 2; ++end) {
      limits_[index(motor)][end] = board_.switches.limit_pressed(motor, end);
    }
    // The interrupt halts at the edge; this covers a switch found pressed by polling alone.
    const uint8_t toward = motors_[index(motor)].toward;
    if (toward != kNoEnd && limits_[index(motor)][toward] && scheduler_.is_running(motor)) {
      scheduler_.halt(motor);
    }
  }
}

void Controller::run_timers(hal::Ticks now) {
  for (uint8_t servo = 1; servo <= proto::kServoCount; ++servo) {
    hal::Ticks& at = servo_release_at_[servo - 1];
    if (at != 0 && now >= at) {
      board_.servos.release(servo);
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
