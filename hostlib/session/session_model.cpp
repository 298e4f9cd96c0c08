// Session: the board model as the session keeps it (session.h) — what the board reports
// (apply), what the host sent (apply_sent), the seed firmware's motions, which report nothing and
// are assumed from their timing (settle_seed_motions), and refusals explained in words. The
// conversation itself (detection, sending, replies, waits) is session.cpp.
#include <algorithm>

#include "hmc/session.h"

namespace hmc {
namespace {

using proto::Reason;

// Seed firmware: how long the host assumes a homing without a step bound may take.
constexpr Millis kSeedHomingTime{20000};

constexpr int64_t kUnitsPerStep = 256;  // positions count 1/256 step

const char* end_name(uint32_t end) { return end == 0 ? "reverse" : "forward"; }

std::string motor_name(uint32_t m) { return "motor " + std::to_string(m); }

Clock::duration seed_duration(uint64_t steps, uint32_t delay_us) {
  const auto us = static_cast<double>(steps) * delay_us * kSeedTimeMargin;
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::micro>(us)) +
         kSeedTimeSlack;
}

}  // namespace

BoardModel::BoardModel() {
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    motor(m).motor = m;
    motor(m).microstep = 16;  // the board's microstep after power-up
  }
  for (uint32_t s = 1; s <= proto::kStripCount; ++s) strips[s - 1].strip = s;
  board.servo1_us = board.servo2_us = proto::servo_pulse_us(90);
}

bool BoardModel::any_moving() const {
  return std::any_of(motors.begin(), motors.end(), [](const MotorStatus& m) { return m.state != MotorState::kIdle; });
}

std::string steps_text(int64_t position) {
  const bool negative = position < 0;
  const uint64_t magnitude = negative ? uint64_t(0) - static_cast<uint64_t>(position) : static_cast<uint64_t>(position);
  std::string text = (negative ? "-" : "") + std::to_string(magnitude / kUnitsPerStep);
  uint64_t rest = magnitude % kUnitsPerStep;
  if (rest != 0) {
    // 1/256 has an exact decimal expansion of at most 8 digits.
    std::string digits;
    for (int i = 0; i < 8 && rest != 0; ++i) {
      rest *= 10;
      digits += static_cast<char>('0' + rest / kUnitsPerStep);
      rest %= kUnitsPerStep;
    }
    text += "." + digits;
  }
  return text;
}

std::string explain_refusal(Reason reason, const Command* command, const BoardModel& model) {
  const StepperMove* move = command != nullptr ? std::get_if<StepperMove>(command) : nullptr;
  switch (reason) {
    case Reason::kLimitPressed:
      if (move != nullptr) {
        const uint32_t end = move->dir == proto::kActionForward ? 1 : 0;
        return motor_name(move->motor) + "'s limit switch at the " + end_name(end) +
               " end is pressed: move it the other way first (or home it)";
      }
      return "a limit switch in the direction of the move is pressed";
    case Reason::kMotorsRunning: {
      if (const auto* set = command != nullptr ? std::get_if<SetPosition>(command) : nullptr) {
        return motor_name(set->motor) + " moves: its position is set at rest; wait for it, or stop it with `hmc stop`";
      }
      std::string moving;
      for (const MotorStatus& m : model.motors) {
        if (m.state != MotorState::kIdle) moving += (moving.empty() ? "" : ", ") + motor_name(m.motor);
      }
      return "homing needs every motor at rest" + (moving.empty() ? std::string() : ", but " + moving + " moves") +
             ": wait for it, or stop it with `hmc stop`";
    }
    case Reason::kEmergencyStop:
      return "the emergency switch is pressed: release it first (stop and LED commands still work)";
    case Reason::kBusy:
      return "the board keeps the seed's rule: servo and LED commands are ignored while a stepper runs; wait "
             "until it stops (`hmc move ... --wait`)";
    case Reason::kRateLimit:
      // Session::explain_rate_limit names the limit with numbers, asking the board for them.
      return "the step rate is beyond what the board can time (its delay range, the motor's max_rate, or its "
             "budget for the moving motors together): use a longer delay, or wait for the other motors";
    case Reason::kSoftLimit:
      return (move != nullptr ? motor_name(move->motor) + "'s" : std::string("the motor's")) +
             " move would end outside its soft travel limits (LIM)";
    case Reason::kNoSwitch:
      return (move != nullptr ? motor_name(move->motor) : std::string("this motor")) +
             " has no limit switch to home against";
    default:
      return std::string("the board refused the line: ") + proto::reason_spec(reason).text;
  }
}

std::string not_homed_cause(const BoardModel& model) {
  return model.board.emergency ? "the emergency switch stopped it" : "the switch was not found";
}

std::string Session::explain_rate_limit(const StepperMove& move) {
  const std::string who = motor_name(move.motor);
  const auto setting = [&](uint32_t motor, uint32_t id) -> std::optional<uint32_t> {
    SessionResult<BoardFrame> got = execute(GetSetting{motor, id});
    const SettingValue* value = got ? std::get_if<SettingValue>(&got.value()) : nullptr;
    if (value == nullptr) return std::nullopt;
    return value->value;
  };
  const bool homing = move.dir == proto::kActionHome;
  uint32_t delay = move.delay_us;
  if (homing && delay == 0) delay = setting(move.motor, proto::kSettingHomeSeek).value_or(0);
  if (!proto::delay_in_range(delay)) {
    return who + "'s delay of " + std::to_string(delay) + " us per step is " +
           (delay < proto::kShortestDelayUs ? "shorter than the shortest" : "longer than the longest") +
           " the board's step timer makes: give " + std::to_string(proto::kShortestDelayUs) + "-" +
           std::to_string(proto::kLongestDelayUs) + " us";
  }
  const uint32_t rate = proto::step_rate(delay);
  const std::string its_rate = who + " would step at " + std::to_string(rate) + " steps/s (" + std::to_string(delay) + " us a step)";
  if (!homing) {
    if (const std::optional<uint32_t> most = setting(move.motor, proto::kSettingMaxRate); most && rate > *most) {
      return its_rate + ", above its max_rate setting of " + std::to_string(*most) + " steps/s: give a delay of " +
             std::to_string(proto::step_rate(*most)) + " us or more (or raise it: SET " + std::to_string(move.motor) +
             " " + std::to_string(proto::kSettingMaxRate) + " RATE)";
    }
  }
  // The step interrupt's budget, shared by every moving motor: ask how fast the others go.
  uint32_t sum = rate;
  const uint32_t accel = homing ? 0 : setting(move.motor, proto::kSettingAccel).value_or(0);
  bool ramping = accel != 0;
  std::string others;
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (m == move.motor || model_.motor(m).state == MotorState::kIdle) continue;
    if (SessionResult<BoardFrame> status = execute(StatusQuery{m}); !status) continue;
    if (model_.motor(m).state == MotorState::kIdle) continue;
    sum += model_.motor(m).rate;
    ramping = ramping || setting(m, proto::kSettingAccel).value_or(0) != 0;
    others += ", " + motor_name(m) + " at " + std::to_string(model_.motor(m).rate) + " now";
  }
  const StepBudgets budgets = step_budgets_in_force();
  const uint32_t budget = budgets.when(ramping);
  const std::string which = ramping ? "its budget while any moving motor ramps, " + std::to_string(budget) +
                                          " steps/s (" + std::to_string(budgets.constant) + " at constant rate)"
                                    : "its budget of " + std::to_string(budget) + " steps/s";
  if (others.empty()) {
    if (rate > budget) {
      return its_rate + (ramping ? " ramping (accel " + std::to_string(accel) + " steps/s^2)" : std::string()) +
             ", above what the board can time: " + which + ": give a delay of " +
             std::to_string(proto::step_rate(budget)) + " us or more" + (ramping ? ", or accel 0" : "");
    }
    return its_rate + " with an acceleration of " + std::to_string(accel) +
           " steps/s^2: the board's step engine cannot plan that ramp: use a longer delay or another acceleration";
  }
  return its_rate + "; with the other moving motors (" + others.substr(2) + ") they would make " +
         std::to_string(sum) + " steps/s or more together, above " + which +
         ": use a longer delay, or wait for the other motors";
}

void Session::apply(const BoardFrame& frame) {
  struct Apply {
    Session& s;
    void operator()(const Ack&) const {}
    void operator()(const Nak&) const {}
    void operator()(const Version& v) const { s.version_ = v; }
    void operator()(const MotorStatus& m) const {
      if (m.motor >= 1 && m.motor <= proto::kMotorCount) s.model_.motor(m.motor) = m;
    }
    void operator()(const BoardStatus& b) const { s.model_.board = b; }
    void operator()(const StripStatus& l) const {
      if (l.strip >= 1 && l.strip <= proto::kStripCount) s.model_.strips[l.strip - 1] = l;
    }
    void operator()(const SettingValue&) const {}
    void operator()(const Booted&) const {
      s.rebooted_ = true;
      s.mode_ = proto::ChecksumMode::kSum;
      s.model_ = BoardModel{};
    }
    void operator()(const MotionEnded& e) const {
      if (e.motor < 1 || e.motor > proto::kMotorCount) return;
      MotorStatus& m = s.model_.motor(e.motor);
      m.state = MotorState::kIdle;
      m.position = e.position;
      m.target = e.position;  // a motion that ended has reached its end, whatever it aimed at
      m.rate = 0;
      m.endless = false;
      s.model_.last_end[e.motor - 1] = e.how;
    }
    void operator()(const HomingEnded& e) const {
      if (e.motor < 1 || e.motor > proto::kMotorCount) return;
      MotorStatus& m = s.model_.motor(e.motor);
      m.state = MotorState::kIdle;
      m.position = e.position;
      m.target = e.position;
      m.homed = e.homed;
      m.rate = 0;
    }
    void operator()(const LimitChanged& e) const {
      if (e.motor < 1 || e.motor > proto::kMotorCount || e.end > 1) return;
      const uint32_t board_bit = 1u << (2 * (e.motor - 1) + e.end);
      const uint32_t motor_bit = 1u << e.end;
      uint32_t& limits = s.model_.board.limits;
      uint32_t& switches = s.model_.motor(e.motor).switches;
      limits = e.pressed ? (limits | board_bit) : (limits & ~board_bit);
      switches = e.pressed ? (switches | motor_bit) : (switches & ~motor_bit);
    }
    void operator()(const EmergencyChanged& e) const { s.model_.board.emergency = e.pressed; }
    void operator()(const DriverFault&) const {}
    void operator()(const WatchdogStatus& w) const { s.model_.watchdog = w; }
    void operator()(const ResetStatus& r) const { s.model_.last_reset = r; }
    void operator()(const ResetEvent& r) const { s.model_.last_reset = r; }
  };
  std::visit(Apply{*this}, frame);
}

void Session::apply_sent(const Command& command) {
  if (const auto* c = std::get_if<ChecksumModeCommand>(&command)) {
    mode_ = static_cast<proto::ChecksumMode>(c->mode);
    if (version_) version_->checksum_mode = mode_;
  } else if (const auto* servo = std::get_if<ServoMove>(&command)) {
    (servo->servo == 1 ? model_.board.servo1_us : model_.board.servo2_us) = proto::servo_pulse_us(servo->angle);
  } else if (const auto* led = std::get_if<LedColor>(&command)) {
    model_.strips[led->strip - 1] = StripStatus{led->strip, led->r, led->g, led->b, led->w};
  } else if (const auto* set = std::get_if<SetPosition>(&command)) {
    MotorStatus& m = model_.motor(set->motor);
    m.position = m.target = set->value();
    m.homed = true;
  }
  const auto* move = std::get_if<StepperMove>(&command);
  if (move == nullptr) return;
  MotorStatus& m = model_.motor(move->motor);
  const Clock::time_point now = Clock::now();
  if (firmware_ == Firmware::kV2) {
    // Events and status replies keep the rest current; the state changes now so a wait that
    // follows at once does not see the motor idle before the board's first event.
    if (move->dir == proto::kActionStop) return;
    if (move->microstep != 0) m.microstep = move->microstep;
    m.state = move->dir == proto::kActionHome ? MotorState::kHoming : MotorState::kMoving;
    model_.last_end[move->motor - 1].reset();
    return;
  }
  // Seed firmware: the model is all the host has. A new command replaces the running one, so
  // the steps the old one made until now count.
  SeedMove& seed = seed_moves_[move->motor - 1];
  if (m.state == MotorState::kMoving && now < seed.end) {
    const auto elapsed = std::chrono::duration_cast<std::chrono::microseconds>(now - seed.start).count();
    const int64_t units = std::max<int64_t>(0, elapsed) / seed.delay_us * kUnitsPerStep / m.microstep;
    const int64_t left = m.target - m.position;
    m.position += m.endless ? seed.sign * units : (left >= 0 ? std::min(units, left) : std::max(-units, left));
  }
  m.state = MotorState::kIdle;
  m.rate = 0;
  m.target = m.position;
  m.endless = false;
  seed = SeedMove{now, now, 1, 1};
  if (move->dir == proto::kActionStop) return;
  if (move->microstep != 0) m.microstep = move->microstep;
  m.rate = 1000000u / std::max<uint32_t>(move->delay_us, 1);
  seed.delay_us = std::max<uint32_t>(move->delay_us, 1);
  if (move->dir == proto::kActionHome) {
    m.state = MotorState::kHoming;
    // A delay of 0 seeks at home_seek_us, which the seed firmware does not let anyone change.
    const uint32_t delay = move->delay_us != 0 ? move->delay_us : proto::kSettings[proto::kSettingHomeSeek - 1].initial;
    seed.end = move->steps > 0 ? now + seed_duration(move->steps, delay) : now + kSeedHomingTime;
    return;
  }
  const int64_t units = static_cast<int64_t>(move->steps) * kUnitsPerStep / m.microstep;
  seed.sign = move->dir == proto::kActionForward ? 1 : -1;
  m.state = MotorState::kMoving;
  m.endless = move->steps == 0;
  m.target = m.endless ? m.position : m.position + seed.sign * units;
  seed.end = m.endless ? Clock::time_point::max() : now + seed_duration(move->steps, move->delay_us);
}

void Session::settle_seed_motions() {
  if (firmware_ != Firmware::kSeed) return;
  const Clock::time_point now = Clock::now();
  for (uint32_t i = 0; i < proto::kMotorCount; ++i) {
    MotorStatus& m = model_.motors[i];
    if (m.state == MotorState::kIdle || now < seed_moves_[i].end) continue;
    if (m.state == MotorState::kHoming) {
      m.position = 0;  // assumed: the seed reports nothing
      m.homed = true;
    } else {
      m.position = m.target;
    }
    m.target = m.position;
    m.state = MotorState::kIdle;
    m.rate = 0;
  }
}

}  // namespace hmc
