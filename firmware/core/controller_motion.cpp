// Controller, motion: STM moves and stops, homing (seek, pull-off, slow locate), the rate
// budget, soft limits, the bookkeeping of ended motions and the boot self-test (controller.h).
#include "controller.h"

namespace hmc::fw {
namespace {

using proto::Reason;

// The token a rule refusal concerns (docs/protocol.md, "Verdicts").
constexpr uint8_t kTokenDir = proto::kTokenFirstValue + 1;
constexpr uint8_t kTokenSteps = proto::kTokenFirstValue + 3;
constexpr uint8_t kTokenDelay = proto::kTokenFirstValue + 4;

// The delay range the host is told of is the step timer's.
static_assert(proto::kShortestDelayUs * hal::kTicksPerMicrosecond == kMinIntervalTicks, "shortest delay");
static_assert(uint64_t{proto::kLongestDelayUs} * hal::kTicksPerMicrosecond <= 0xFFFFFFFFu &&
                  uint64_t{proto::kLongestDelayUs + 1} * hal::kTicksPerMicrosecond > 0xFFFFFFFFu,
              "longest delay: the most a 32-bit interval holds");

// Ticks per step for `delay_us`, or 0 when the timer cannot produce it.
uint32_t interval_for(uint32_t delay_us) {
  if (!proto::delay_in_range(delay_us)) return 0;
  return delay_us * hal::kTicksPerMicrosecond;
}

uint32_t rate_for(uint32_t delay_us) { return proto::step_rate(delay_us); }

uint32_t how_from(MoveEnd end) {
  return end == MoveEnd::kCompleted ? proto::kEndCompleted : proto::kEndStopped;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// STM

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

  Motor& mo = motors_[index(motor)];
  const bool reverse = command.dir == proto::kActionReverse;
  const uint8_t end = reverse ? 0 : 1;
  if (proto::motor_has_switches(motor) && limits_[index(motor)][end]) {
    return {Reason::kLimitPressed, kTokenDir};
  }
  const uint32_t interval = interval_for(command.delay_us);
  const uint32_t rate = interval == 0 ? 0 : rate_for(command.delay_us);
  if (interval == 0 || rate > mo.settings[proto::kSettingMaxRate - 1]) {
    return {Reason::kRateLimit, kTokenDelay};
  }
  uint32_t steps = command.steps;
  if (mo.soft_limits) {
    // The end of the move must stay within [low, high]; a run until stopped becomes a move
    // to the limit.
    const int64_t units = 256 / static_cast<int64_t>(command.microstep);
    const int64_t here = scheduler_.position(motor);
    const int64_t room = reverse ? here - mo.soft_low : mo.soft_high - here;
    const int64_t most = room < 0 ? 0 : room / units;
    if (steps == 0) {
      if (most == 0) return {Reason::kSoftLimit, kTokenSteps};
      steps = most > proto::kIntMax ? proto::kIntMax : static_cast<uint32_t>(most);
    } else if (static_cast<int64_t>(steps) > most) {
      return {Reason::kSoftLimit, kTokenSteps};
    }
  }
  const MoveSpec move{reverse, static_cast<uint16_t>(command.microstep), steps, interval,
                      mo.settings[proto::kSettingAccel - 1]};
  return {start_move(motor, move, rate, MotorState::kMoving), kTokenDelay};
}

void Controller::stop_motor(uint8_t motor) {
  Motor& mo = motors_[index(motor)];
  if (mo.state == MotorState::kChanging) mo.state = MotorState::kMoving;  // drop the waiting move
  scheduler_.stop(motor);
}

// ---------------------------------------------------------------------------------------
// Homing: seek the home switch, zero there; then optionally pull off and locate it slowly.

Controller::Refusal Controller::home(const StepperCommand& command) {
  const uint8_t motor = command.motor;
  if (any_moving()) return {Reason::kMotorsRunning, kTokenDir};
  Motor& mo = motors_[index(motor)];
  const uint8_t end = static_cast<uint8_t>(mo.settings[proto::kSettingHomeEnd - 1]);
  mo.homed = false;
  if (limits_[index(motor)][end] && mo.settings[proto::kSettingHomePullOff - 1] == 0) {
    scheduler_.set_position(motor, 0);  // already on the home switch
    mo.homed = true;
    send_homing_ended(motor, true);
    return {};
  }
  const uint32_t delay_us =
      command.delay_us != 0 ? command.delay_us : mo.settings[proto::kSettingHomeSeek - 1];
  const uint32_t interval = interval_for(delay_us);
  if (interval == 0) return {Reason::kRateLimit, kTokenDelay};
  const uint32_t microstep = command.microstep != 0 ? command.microstep : mo.microstep;
  mo.home_delay_us = delay_us;
  mo.home_phase = HomePhase::kSeek;
  if (limits_[index(motor)][end]) {  // on the switch with a pull-off to do
    scheduler_.set_position(motor, 0);
    mo.homed = true;
    homing_step(motor);
    return {};
  }
  // Seeking runs at constant rate: the switch halts it where it closed.
  const MoveSpec seek{end == 0, static_cast<uint16_t>(microstep), command.steps, interval, 0};
  return {start_move(motor, seek, rate_for(delay_us), MotorState::kHoming), kTokenDelay};
}

// The next homing phase, once the previous one has ended at rest.
void Controller::homing_step(uint8_t motor) {
  Motor& mo = motors_[index(motor)];
  const uint8_t end = static_cast<uint8_t>(mo.settings[proto::kSettingHomeEnd - 1]);
  const bool on_switch = limits_[index(motor)][end] || board_.switches.limit_pressed(motor, end);
  const uint32_t pull_off = mo.settings[proto::kSettingHomePullOff - 1];
  const uint32_t locate_us = mo.settings[proto::kSettingHomeLocate - 1];
  const uint16_t microstep = static_cast<uint16_t>(mo.microstep);

  if (mo.home_phase == HomePhase::kSeek || mo.home_phase == HomePhase::kLocate) {
    if (!on_switch || emergency_) {
      mo.homed = false;
      send_homing_ended(motor, false);
      return;
    }
    scheduler_.set_position(motor, 0);
    mo.homed = true;
    if (mo.home_phase == HomePhase::kLocate || pull_off == 0) {
      send_homing_ended(motor, true);
      return;
    }
    // The pull-off moves toward the other end; a pressed switch there ends homing here, zeroed,
    // rather than letting a step go toward it before the switch poll halts the motor.
    const uint8_t other = end == 0 ? 1 : 0;
    if (limits_[index(motor)][other] || board_.switches.limit_pressed(motor, other)) {
      send_homing_ended(motor, true);
      return;
    }
    mo.home_phase = HomePhase::kPullOff;
    const MoveSpec back{end == 1, microstep, pull_off, interval_for(mo.home_delay_us), 0};
    if (start_move(motor, back, rate_for(mo.home_delay_us), MotorState::kHoming) != Reason::kOk) {
      send_homing_ended(motor, true);
    }
    return;
  }
  // Pulled off: done, or re-approach slowly (at most twice the pull-off) and zero again.
  const uint32_t locate_interval = interval_for(locate_us);
  if (locate_us == 0 || locate_interval == 0 || emergency_ || on_switch) {
    send_homing_ended(motor, mo.homed);
    return;
  }
  mo.home_phase = HomePhase::kLocate;
  const uint32_t bound = pull_off > proto::kIntMax / 2 ? proto::kIntMax : 2 * pull_off + 1;
  const MoveSpec locate{end == 0, microstep, bound, locate_interval, 0};
  if (start_move(motor, locate, rate_for(locate_us), MotorState::kHoming) != Reason::kOk) {
    send_homing_ended(motor, mo.homed);
  }
}

// ---------------------------------------------------------------------------------------
// Starting moves

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
  mo.halt_cause = 0;
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
    ramping = ramping || mo.settings[proto::kSettingAccel - 1] != 0;
  }
  return sum <= proto::step_budget(ramping);
}

bool Controller::any_moving() const {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    if (scheduler_.is_running(motor)) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------
// Ended motions

void Controller::check_motions() {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    Motor& mo = motors_[index(motor)];
    const uint32_t finished = scheduler_.finished(motor);
    if (finished == mo.seen_finished) continue;
    mo.seen_finished = finished;
    if (scheduler_.is_running(motor)) continue;  // an earlier motion; the one running is newer
    // A switch's interrupt halts at once and its event (EVE, EVL) is sent by check_switches():
    // when the interrupt came after this poll's check_switches(), report the switch now, so
    // its event always comes before the end it caused.
    const uint8_t cause = mo.halt_cause;
    if (cause == proto::kEndEmergency || cause == proto::kEndLimit) check_switches();
    motion_ended(motor);
  }
  advance_self_test();
}

// A motion of `motor` ended and it rests: homing goes on, a waiting move starts, or the end
// is reported (EVD: completed, stopped, or halted by a switch).
void Controller::motion_ended(uint8_t motor) {
  Motor& mo = motors_[index(motor)];
  const MotorState state = mo.state;
  if (state == MotorState::kSelfTest) return;  // advance_self_test() decides
  mo.state = MotorState::kIdle;
  mo.rate = 0;
  mo.toward = kNoEnd;
  switch (state) {
    case MotorState::kHoming:
      homing_step(motor);
      return;
    case MotorState::kChanging: {
      const uint8_t end = mo.pending.reverse ? 0 : 1;
      const bool blocked = proto::motor_has_switches(motor) && limits_[index(motor)][end];
      if (emergency_ || blocked ||
          start_move(motor, mo.pending, mo.pending_rate, mo.pending_state) != Reason::kOk) {
        send_motion_ended(motor, emergency_ ? proto::kEndEmergency : proto::kEndDropped);
      }
      return;
    }
    default:
      break;
  }
  const MoveEnd end = scheduler_.last_end(motor);
  // The watchdog's stop brakes like any stop, yet its end is the watchdog's.
  const bool halted = end == MoveEnd::kHalted || mo.halt_cause == proto::kEndWatchdog;
  send_motion_ended(motor, halted && mo.halt_cause != 0 ? mo.halt_cause : how_from(end));
}

// ---------------------------------------------------------------------------------------
// Self-test

// Phase 1: every motor half a turn forward.
void Controller::start_self_test() {
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    const MoveSpec forward{false, static_cast<uint16_t>(kBootMicrostep), kSelfTestSteps,
                           interval_for(kSelfTestDelayUs), 0};
    if (start_move(motor, forward, rate_for(kSelfTestDelayUs), MotorState::kSelfTest) == Reason::kOk) {
      self_test_phase_ = 1;
    }
  }
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

// Phase 1 runs every motor forward; when all rest, phase 2 brings each back as far as it went.
void Controller::advance_self_test() {
  if (self_test_phase_ == 0) return;
  // A motor at rest whose end check_motions() has not seen yet (the interrupt took the end
  // marker after that check read `finished`) waits for the next poll, which sees it while the
  // motor is still in the self-test: otherwise that end would be reported as an EVD of its own.
  // (The interrupt counts `finished` before it marks the lane at rest, so read after.)
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    const Motor& mo = motors_[index(motor)];
    if (mo.state != MotorState::kSelfTest) continue;
    if (scheduler_.is_running(motor) || scheduler_.finished(motor) != mo.seen_finished) return;
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

}  // namespace hmc::fw
