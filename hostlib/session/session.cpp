// Session: firmware detection, the board model, checks before sending, replies and waits.
#include "hmc/session.h"

#include <algorithm>

#include "hmc/codec.h"

namespace hmc {
namespace {

using proto::Reason;

// No reply to VER within this long means a board that answers nothing: the seed firmware.
// It covers the line's wire time at 9600 baud and a network bridge's delay.
constexpr Millis kDetectTimeout{250};
// Longest single read while waiting, so interrupts and deadlines are seen promptly.
constexpr Millis kSlice{50};
// While a motion runs and the board says nothing for this long, ask it (an event may be lost).
constexpr Millis kStatusEvery{500};
// Longest a stopped motor may brake before the host reports it as still moving.
constexpr Millis kBrakeLimit{10000};
// Seed firmware: how long the host assumes a homing without a step bound may take.
constexpr Millis kSeedHomingTime{20000};

constexpr int64_t kUnitsPerStep = 256;  // positions count 1/256 step

const char* end_name(uint32_t end) { return end == 0 ? "reverse" : "forward"; }

std::string motor_name(uint32_t m) { return "motor " + std::to_string(m); }

SessionError make_error(SessionError::Kind kind, std::string message, Reason reason = Reason::kOk) {
  SessionError e;
  e.kind = kind;
  e.message = std::move(message);
  e.reason = reason;
  return e;
}

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

Session::Session(std::unique_ptr<Transport> transport, const SessionOptions& options)
    : transport_(std::move(transport)), options_(options) {}

Session::~Session() {
  if (watchdog_armed()) (void)disarm_watchdog();  // best effort: the link may be gone
}

bool Session::supports(proto::Feature feature) const {
  return firmware_ == Firmware::kV2 && version_ && version_->protocol >= proto::feature_spec(feature).since;
}

SessionResult<Done> Session::require(proto::Feature feature) const {
  if (supports(feature)) return Done{};
  const proto::FeatureSpec& spec = proto::feature_spec(feature);
  const std::string board = firmware_ == Firmware::kSeed
                                ? "the board runs the original (seed) firmware"
                                : "the board speaks protocol " + std::to_string(version_ ? version_->protocol : 0);
  return make_error(SessionError::Kind::kTooOld, "the board's firmware is too old for this: reflash (" +
                                                     std::string(spec.text) + " needs protocol " +
                                                     std::to_string(spec.since) + "; " + board + ")");
}

SessionResult<Done> Session::arm_watchdog(Millis timeout) {
  if (SessionResult<Done> ok = require(proto::Feature::kLinkWatchdog); !ok) return ok;
  const uint32_t ms = static_cast<uint32_t>(std::clamp<int64_t>(timeout.count(), 1, proto::kWatchdogMaxMs));
  if (SessionResult<BoardFrame> armed = execute(WatchdogCommand{ms}); !armed) return armed.error();
  if (model_.watchdog) *model_.watchdog = WatchdogStatus{ms, false};
  if (!watchdog_armed()) {
    keep_alive_stop_ = false;
    keep_alive_period_ = Millis{std::max<uint32_t>(ms / 4, 1)};
    keep_alive_ = std::thread([this] { keep_alive(); });
  }
  return Done{};
}

SessionResult<Done> Session::disarm_watchdog() {
  stop_keep_alive();
  SessionResult<BoardFrame> off = execute(WatchdogCommand{0});
  if (!off) return off.error();
  if (model_.watchdog) model_.watchdog->timeout_ms = 0;
  return Done{};
}

void Session::stop_keep_alive() {
  if (!keep_alive_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(transport_mutex_);
    keep_alive_period_ = Millis{0};
  }
  {
    const std::lock_guard<std::mutex> lock(keep_alive_mutex_);
    keep_alive_stop_ = true;
  }
  keep_alive_wake_.notify_all();
  keep_alive_.join();
}

// A blank line feeds the board's watchdog and gets no reply, so it never disturbs the count of
// replies the main thread matches to its lines.
void Session::keep_alive() {
  std::unique_lock<std::mutex> wake(keep_alive_mutex_);
  while (!keep_alive_wake_.wait_for(wake, keep_alive_period_ / 2, [this] { return keep_alive_stop_; })) {
    const std::lock_guard<std::mutex> lock(transport_mutex_);
    keep_alive_if_due();
  }
}

void Session::keep_alive_if_due() {
  if (keep_alive_period_.count() == 0 || Clock::now() - last_write_ < keep_alive_period_) return;
  (void)transport_->write("\n");  // a failed link is the reader's to report
  last_write_ = Clock::now();
}

SessionResult<std::unique_ptr<Session>> Session::open(std::unique_ptr<Transport> transport,
                                                       const SessionOptions& options) {
  std::unique_ptr<Session> session(new Session(std::move(transport), options));
  if (options.firmware == FirmwareChoice::kSeed || session->transport_->seed_firmware()) {
    session->firmware_ = Firmware::kSeed;
    return session;
  }
  if (SessionResult<Done> detected = session->detect(); !detected) return detected.error();
  if (session->firmware_ == Firmware::kSeed) {
    // Silence is never success: a wrong port, an unpowered board and a wrong baud rate are
    // silent too. Only the user can say the board runs the original firmware.
    return make_error(SessionError::Kind::kNoReply,
                      "no reply to VER from " + session->transport_->description() + " within " +
                          std::to_string(kDetectTimeout.count()) +
                          " ms: this is not a board, or it is not powered, or not at this baud rate (--baud); or "
                          "it runs the original (seed) firmware, which answers nothing: then say so with "
                          "--firmware seed");
  }
  if (SessionResult<Done> refreshed = session->refresh(); !refreshed) return refreshed.error();
  return session;
}

SessionResult<Done> Session::detect() {
  // Whatever an earlier program left unread is not an answer to this session; nor is the end of
  // a line the board had begun before the port was opened (its start never reached us).
  detecting_ = true;
  if (SessionResult<std::vector<BoardFrame>> drained = pump(Millis{20}); !drained) {
    detecting_ = false;
    return drained.error();
  }
  pending_replies_.clear();

  const SessionResult<Done> result = detect_firmware();
  detecting_ = false;
  return result;
}

SessionResult<Done> Session::detect_firmware() {
  // The first VER goes out with the seed's sum; a board in CRC-16 mode refuses it, in CRC-16,
  // and the second VER uses the mode its answer came in.
  for (int attempt = 0; attempt < 2; ++attempt) {
    const Result<std::string, Diagnostic> frame = encode(VersionQuery{}, mode_);
    if (SessionResult<Done> sent = write_line(frame.value(), std::nullopt); !sent) return sent.error();
    const Clock::time_point deadline = Clock::now() + kDetectTimeout;
    while (pending_replies_.empty() && Clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<Millis>(deadline - Clock::now());
      if (SessionResult<std::vector<BoardFrame>> got = pump(std::min(left + Millis{1}, kSlice)); !got) {
        return got.error();
      }
      if (interrupted()) return interrupted_error();
    }
    if (pending_replies_.empty()) {
      if (attempt > 0) break;
      in_flight_.clear();
      in_flight_bytes_ = 0;
      firmware_ = Firmware::kSeed;
      mode_ = proto::ChecksumMode::kSum;
      return Done{};
    }
    const BoardFrame reply = pending_replies_.front().frame;
    pending_replies_.pop_front();
    if (const Version* v = std::get_if<Version>(&reply)) {
      firmware_ = Firmware::kV2;
      version_ = *v;
      mode_ = v->checksum_mode;
      return Done{};
    }
    if (!std::holds_alternative<Nak>(reply) || mode_ == proto::ChecksumMode::kSum) break;
  }
  return make_error(SessionError::Kind::kNoReply,
                    "the board at " + transport_->description() + " did not answer VER as expected");
}

std::string Session::description() const {
  std::string text = transport_->description();
  if (firmware_ == Firmware::kSeed) return text + ", seed firmware (it sends no replies)";
  if (version_) {
    text += ", firmware " + firmware_version_text(version_->firmware) + ", protocol " +
            std::to_string(version_->protocol);
    if (version_->legacy) text += ", legacy rules";
  }
  return text;
}

uint32_t Session::max_rate() const { return version_ ? version_->max_rate : 50000; }

bool Session::legacy_rules() const { return firmware_ == Firmware::kSeed || (version_ && version_->legacy); }

SessionResult<Done> Session::write_line(const std::string& line, std::optional<Command> command) {
  if (options_.on_send) options_.on_send(line);
  Status written = Done{};
  {
    const std::lock_guard<std::mutex> lock(transport_mutex_);
    written = transport_->write(line + "\n");
    last_write_ = Clock::now();
  }
  if (!written) return link_error(written.error().message);
  if (firmware_ == Firmware::kSeed) {
    if (command) apply_sent(*command);
  } else if (!is_blank(line)) {
    in_flight_.push_back(InFlight{std::move(command), line.size() + 1, ++lines_written_});
    in_flight_bytes_ += line.size() + 1;
  }
  return Done{};
}

SessionResult<std::vector<BoardFrame>> Session::pump(Millis timeout) {
  Result<std::string> bytes = std::string();
  {
    const std::lock_guard<std::mutex> lock(transport_mutex_);
    // The keep-alive thread may not win the lock between two reads: the reader sends it too.
    keep_alive_if_due();
    bytes = transport_->read(timeout);
  }
  if (!bytes) return link_error(bytes.error().message);
  splitter_.feed(*bytes);
  std::vector<BoardFrame> frames;
  while (std::optional<Line> line = splitter_.next()) {
    Result<BoardFrame, Diagnostic> frame = decode_board_frame(line->text, mode_);
    if (!frame && detecting_) {
      // A board left in the other checksum mode by an earlier program answers in that mode.
      const proto::ChecksumMode other =
          mode_ == proto::ChecksumMode::kSum ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum;
      if (Result<BoardFrame, Diagnostic> retry = decode_board_frame(line->text, other); retry) {
        mode_ = other;
        frame = std::move(retry);
      }
    }
    if (options_.on_line) options_.on_line(line->text, frame);
    // Before VER is answered no reply is counted yet: a line cut short by the opening of the
    // port is passed over (if it was the answer, detection times out and says so).
    if (!frame && detecting_) continue;
    if (!frame) {
      // Counting replies is only possible if every line is read: a garbled one ends the session.
      return make_error(SessionError::Kind::kLink,
                        "the board sent a line that is not a frame (" + frame.error().message + "): '" +
                            line->text + "'; is the baud rate right (--baud)?");
    }
    apply(*frame);
    if (!is_event(*frame)) {
      // The reply to the oldest line in flight: an accepted command changes the model now,
      // before any event that follows it in the stream.
      uint64_t answered = 0;
      if (!in_flight_.empty()) {
        const InFlight& oldest = in_flight_.front();
        if (oldest.command && std::holds_alternative<Ack>(*frame)) apply_sent(*oldest.command);
        answered = oldest.line;
        in_flight_bytes_ -= oldest.bytes;
        in_flight_.pop_front();
      }
      pending_replies_.push_back(Reply{answered, *frame});
    }
    frames.push_back(std::move(*frame));
  }
  return frames;
}

SessionResult<BoardFrame> Session::await_reply(std::string_view sent, uint64_t line) {
  const Clock::time_point deadline = Clock::now() + options_.reply_timeout;
  const auto pass_over_earlier = [&] {
    while (!pending_replies_.empty() && pending_replies_.front().line < line) pending_replies_.pop_front();
  };
  for (pass_over_earlier(); pending_replies_.empty(); pass_over_earlier()) {
    if (Clock::now() >= deadline) {
      return make_error(SessionError::Kind::kNoReply,
                        "no reply from the board within " + std::to_string(options_.reply_timeout.count()) +
                            " ms to " + std::string(sent) + " (it answered before: is it still powered and connected?)");
    }
    const auto left = std::chrono::duration_cast<Millis>(deadline - Clock::now());
    if (SessionResult<std::vector<BoardFrame>> got = pump(std::min(left + Millis{1}, kSlice)); !got) return got.error();
  }
  BoardFrame reply = pending_replies_.front().frame;
  pending_replies_.pop_front();
  return reply;
}

SessionResult<Done> Session::check(const Command& command) const {
  if (Result<Command, Diagnostic> valid = validate(command); !valid) {
    return make_error(SessionError::Kind::kInvalid, valid.error().message, valid.error().reason);
  }
  const auto refuse = [&](Reason reason) {
    return make_error(SessionError::Kind::kRefused, explain_refusal(reason, &command, model_), reason);
  };
  const bool know_switches = firmware_ == Firmware::kV2;
  if (const auto* move = std::get_if<StepperMove>(&command)) {
    const MotorStatus& motor = model_.motor(move->motor);
    if (move->dir == proto::kActionForward || move->dir == proto::kActionReverse) {
      if (know_switches && model_.board.emergency) return refuse(Reason::kEmergencyStop);
      const uint32_t end = move->dir == proto::kActionForward ? 1 : 0;
      if (know_switches && ((motor.switches >> end) & 1u) != 0) return refuse(Reason::kLimitPressed);
    } else if (move->dir == proto::kActionHome) {
      if (know_switches && model_.board.emergency) return refuse(Reason::kEmergencyStop);
      if (model_.any_moving()) return refuse(Reason::kMotorsRunning);
    }
  } else if (const auto* set = std::get_if<SetPosition>(&command)) {
    if (SessionResult<Done> ok = require(proto::Feature::kSetPosition); !ok) return ok;
    if (model_.motor(set->motor).state != MotorState::kIdle) return refuse(Reason::kMotorsRunning);
  } else if (std::holds_alternative<ServoMove>(command)) {
    if (know_switches && model_.board.emergency) return refuse(Reason::kEmergencyStop);
    if (legacy_rules() && model_.any_moving()) return refuse(Reason::kBusy);
  } else if (std::holds_alternative<LedColor>(command)) {
    if (legacy_rules() && model_.any_moving()) return refuse(Reason::kBusy);
  } else if (firmware_ == Firmware::kSeed && command_id(command) > proto::CommandId::kLed) {
    return make_error(SessionError::Kind::kRefused,
                      std::string(command_spec(command).name) + " is a protocol v2 command: the seed firmware does not know it",
                      Reason::kUnknownCommand);
  } else if (const auto* query = std::get_if<StatusQuery>(&command)) {
    // A unit a later protocol brought: an older board would refuse it as out of range.
    if (const proto::FeatureSpec* brought = proto::status_unit_feature(query->unit)) {
      if (SessionResult<Done> ok = require(brought->feature); !ok) return ok;
    }
  }
  return Done{};
}

SessionResult<BoardFrame> Session::execute(const Command& command) {
  settle_seed_motions();
  if (SessionResult<Done> ok = check(command); !ok) return ok.error();
  const Result<std::string, Diagnostic> frame = encode(command, mode_);
  if (SessionResult<Done> sent = write_line(frame.value(), command); !sent) return sent.error();
  if (firmware_ == Firmware::kSeed) return BoardFrame{Ack{}};
  SessionResult<BoardFrame> reply = await_reply(frame.value(), lines_written_);
  if (!reply) return reply;
  if (const Nak* nak = std::get_if<Nak>(&reply.value())) {
    const auto* move = std::get_if<StepperMove>(&command);
    const Reason reason = nak->reason;
    return make_error(SessionError::Kind::kNak,
                      reason == Reason::kRateLimit && move != nullptr ? explain_rate_limit(*move)
                                                                      : explain_refusal(reason, &command, model_),
                      reason);
  }
  return reply;
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
  const uint32_t budget = proto::step_budget(ramping);
  const std::string which = ramping ? "its budget while any moving motor ramps, " + std::to_string(budget) +
                                          " steps/s (" + std::to_string(proto::kMaxStepRate) + " at constant rate)"
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

SessionResult<BoardFrame> Session::send_line(std::string_view line) {
  settle_seed_motions();
  std::string text(line);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const Result<Decoded, Diagnostic> decoded = decode(text, mode_);
  std::optional<Command> command;
  if (decoded) command = decoded->command;
  if (SessionResult<Done> sent = write_line(text, command); !sent) return sent.error();
  if (firmware_ == Firmware::kSeed) return BoardFrame{Ack{}};
  if (is_blank(text)) return BoardFrame{Ack{}};  // a blank line gets no reply
  SessionResult<BoardFrame> reply = await_reply(text, lines_written_);
  if (!reply) return reply;
  if (const Nak* nak = std::get_if<Nak>(&reply.value())) {
    const StepperMove* move = decoded ? std::get_if<StepperMove>(&decoded->command) : nullptr;
    const Reason reason = nak->reason;
    return make_error(SessionError::Kind::kNak,
                      (reason == Reason::kRateLimit && move != nullptr
                           ? explain_rate_limit(*move)
                           : explain_refusal(reason, decoded ? &decoded->command : nullptr, model_)) +
                          " (token " +
                          std::to_string(nak->token) + ", byte " + std::to_string(nak->offset) + ")",
                      nak->reason);
  }
  return reply;
}

SessionResult<Done> Session::refresh() {
  if (firmware_ == Firmware::kSeed) return Done{};
  // Every unit the board's protocol has (kFeatures): 1-6, 7 from protocol 3, 8 from protocol 4.
  const uint32_t last = proto::status_unit_max(version_ ? version_->protocol : 0);
  for (uint32_t unit = 1; unit <= last; ++unit) {
    SessionResult<BoardFrame> reply = execute(StatusQuery{unit});
    if (!reply) return reply.error();
  }
  model_.reported = true;
  return Done{};
}

SessionResult<Done> Session::wait_until_idle(const std::vector<uint32_t>& motors, std::optional<Millis> limit) {
  return wait(
      [&] {
        return std::none_of(motors.begin(), motors.end(),
                            [&](uint32_t m) { return model_.motor(m).state != MotorState::kIdle; });
      },
      limit);
}

SessionResult<Done> Session::wait(const std::function<bool()>& done, std::optional<Millis> limit) {
  const Clock::time_point start = Clock::now();
  rebooted_ = false;
  Clock::time_point last_heard = Clock::now();
  for (;;) {
    settle_seed_motions();
    if (done()) return Done{};
    if (interrupted()) return interrupted_error();
    if (limit && Clock::now() - start > *limit) {
      return stopping(make_error(SessionError::Kind::kNoReply, "the motion did not end within " +
                                                                   std::to_string(limit->count()) +
                                                                   " ms; every motor was sent a stop"));
    }
    // Seed firmware: nothing will arrive, but reading notices a link that fails.
    SessionResult<std::vector<BoardFrame>> frames = pump(kSlice);
    if (!frames) return stopping(frames.error());  // the link may be gone, but if it is not...
    if (rebooted_) {
      return make_error(SessionError::Kind::kLink,
                        "the board restarted during the motion (power or reset): its positions are lost");
    }
    if (!frames->empty()) last_heard = Clock::now();
    if (firmware_ == Firmware::kV2 && Clock::now() - last_heard >= kStatusEvery) {
      // A lost event would leave a motor "moving" here for ever: ask the moving ones.
      for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
        if (model_.motor(m).state == MotorState::kIdle) continue;
        if (SessionResult<BoardFrame> status = execute(StatusQuery{m}); !status) return stopping(status.error());
      }
      last_heard = Clock::now();
    }
  }
}

SessionResult<Done> Session::stop_all() { return stop({1, 2, 3}); }

SessionResult<Done> Session::stop(const std::vector<uint32_t>& motors) {
  // Stops go out first, all of them, then the replies are read: the motors halt together.
  std::vector<std::string> sent;
  std::vector<uint64_t> numbers;
  for (const uint32_t m : motors) {
    const StepperMove stop{m, proto::kActionStop, 0, 0, 0};
    const std::string frame = encode(stop, mode_).value();
    if (SessionResult<Done> written = write_line(frame, Command{stop}); !written) return written.error();
    sent.push_back(frame);
    numbers.push_back(lines_written_);
  }
  for (size_t i = 0; i < sent.size() && firmware_ == Firmware::kV2; ++i) {
    SessionResult<BoardFrame> reply = await_reply(sent[i], numbers[i]);
    if (!reply) return reply.error();
  }
  if (firmware_ == Firmware::kV2) {
    for (const uint32_t m : motors) {
      if (SessionResult<BoardFrame> status = execute(StatusQuery{m}); !status) return status.error();
    }
    // A motor with an acceleration brakes: its position is final only once its end event came.
    // No interrupt check here (the flag that brought us here stays raised).
    const Clock::time_point deadline = Clock::now() + kBrakeLimit;
    while (model_.any_moving() && Clock::now() < deadline) {
      if (SessionResult<std::vector<BoardFrame>> got = pump(kSlice); !got) return got.error();
      pending_replies_.clear();
    }
    if (model_.any_moving()) {
      return make_error(SessionError::Kind::kNoReply, "a motor still moved " + std::to_string(kBrakeLimit.count()) +
                                                          " ms after its stop");
    }
  }
  return Done{};
}

SessionResult<Done> Session::listen(Millis duration) {
  const Clock::time_point deadline = Clock::now() + duration;
  while (Clock::now() < deadline && !interrupted()) {
    const auto left = std::chrono::duration_cast<Millis>(deadline - Clock::now());
    if (SessionResult<std::vector<BoardFrame>> got = pump(std::min(left + Millis{1}, kSlice)); !got) {
      return got.error();
    }
    pending_replies_.clear();  // nothing was asked: replies here belong to nobody
  }
  return Done{};
}

SessionResult<Session::StreamReport> Session::stream(const std::vector<Command>& commands, bool pipelined) {
  StreamReport report;
  std::vector<std::string> lines;
  lines.reserve(commands.size());
  for (size_t i = 0; i < commands.size(); ++i) {
    Result<std::string, Diagnostic> frame = encode(commands[i], mode_);
    if (!frame) {
      SessionError e = make_error(SessionError::Kind::kInvalid,
                                  "command " + std::to_string(i + 1) + ": " + frame.error().message, frame.error().reason);
      return e;
    }
    lines.push_back(std::move(frame.value()));
  }
  if (firmware_ == Firmware::kSeed) {
    // Nothing comes back: each line goes out once the one before has had its wire time.
    for (size_t i = 0; i < lines.size(); ++i) {
      if (interrupted()) return interrupted_error();
      const Clock::time_point start = Clock::now();
      if (SessionResult<Done> sent = write_line(lines[i], commands[i]); !sent) return sent.error();
      ++report.sent;
      ++report.accepted;
      const auto wire = std::chrono::duration<double>(static_cast<double>(lines[i].size() + 1) * 10.0 / options_.baud);
      const Clock::time_point due = start + std::chrono::duration_cast<Clock::duration>(wire);
      while (Clock::now() < due) {
        const auto left = std::chrono::duration_cast<Millis>(due - Clock::now());
        if (SessionResult<std::vector<BoardFrame>> got = pump(std::max(left, Millis{0})); !got) return got.error();
      }
    }
    return report;
  }
  const size_t window = version_ && version_->line_max > 0 ? version_->line_max : proto::kLineMax;
  pending_replies_.clear();
  struct Waiting {
    size_t index;   // in `commands`
    uint64_t line;  // the line's number in the session
  };
  std::deque<Waiting> waiting;  // this stream's lines not yet answered, oldest first
  std::vector<Reason> reasons_after;  // why each of report.refused_after was refused
  std::optional<Reason> reason;       // why report.refused was
  std::vector<bool> started(proto::kMotorCount, false);  // motors an accepted line set moving
  size_t next = 0;
  Clock::time_point last_reply = Clock::now();
  while ((!report.refused && next < lines.size()) || !waiting.empty()) {
    if (interrupted()) return interrupted_error();
    // Character counting: send while the unanswered bytes leave room for the next line.
    const auto room = [&] {
      if (waiting.empty()) return true;
      return pipelined && in_flight_bytes_ + lines[next].size() + 1 <= window;
    };
    while (!report.refused && next < lines.size() && room()) {
      if (SessionResult<Done> sent = write_line(lines[next], commands[next]); !sent) return sent.error();
      waiting.push_back(Waiting{next++, lines_written_});
      ++report.sent;
    }
    // A board that stops answering or a link that fails mid-stream: the motors are sent a stop.
    if (SessionResult<std::vector<BoardFrame>> got = pump(Millis{5}); !got) return stopping(got.error());
    if (!pending_replies_.empty()) last_reply = Clock::now();
    while (!pending_replies_.empty() && !waiting.empty()) {
      const Reply answer = pending_replies_.front();
      pending_replies_.pop_front();
      if (answer.line < waiting.front().line) continue;  // an earlier line's, late
      const BoardFrame& reply = answer.frame;
      const size_t index = waiting.front().index;
      waiting.pop_front();
      if (const Nak* nak = std::get_if<Nak>(&reply)) {
        // Explained once the stream is over: explaining may ask the board.
        if (!report.refused) {
          report.refused = index;
          reason = nak->reason;
        } else {
          report.refused_after.push_back(index);
          reasons_after.push_back(nak->reason);
        }
      } else {
        ++report.accepted;
        const auto* move = std::get_if<StepperMove>(&commands[index]);
        if (move != nullptr && move->dir != proto::kActionStop) started[move->motor - 1] = true;
      }
    }
    if (!waiting.empty() && Clock::now() - last_reply > options_.reply_timeout) {
      return stopping(make_error(SessionError::Kind::kNoReply,
                        "no reply from the board within " + std::to_string(options_.reply_timeout.count()) +
                            " ms while streaming (line " + std::to_string(waiting.front().index + 1) + " of " +
                            std::to_string(lines.size()) + " unanswered); every motor was sent a stop"));
    }
  }
  if (!report.refused) return report;
  // Explained while the board is as it was when it refused (a rate refusal asks it for numbers).
  const auto why = [&](size_t index, Reason r) {
    const auto* move = std::get_if<StepperMove>(&commands[index]);
    return r == Reason::kRateLimit && move != nullptr ? explain_rate_limit(*move)
                                                      : explain_refusal(r, &commands[index], model_);
  };
  report.why = why(*report.refused, *reason);
  for (size_t i = 0; i < report.refused_after.size(); ++i) {
    report.why_after.push_back(why(report.refused_after[i], reasons_after[i]));
  }
  // Giving up never leaves a motor running: what the stream started is stopped.
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (started[m - 1]) report.stopped.push_back(m);
  }
  if (!report.stopped.empty()) {
    if (SessionResult<Done> stopped = stop(report.stopped); !stopped) return stopped.error();
  }
  return report;
}

SessionError Session::interrupted_error() {
  SessionError e = make_error(SessionError::Kind::kInterrupted, "interrupted");
  // The flag stays raised: stop_all must not look at it, and does not.
  if (SessionResult<Done> stopped = stop_all(); !stopped) {
    e.message += "; sending stop to every motor failed: " + stopped.error().message;
  } else {
    e.message += "; every motor was sent a stop";
  }
  return e;
}

SessionError Session::stopping(SessionError error) {
  (void)stop_all();  // best effort: the error being reported is the one that matters
  return error;
}

SessionError Session::link_error(const std::string& message) {
  return make_error(SessionError::Kind::kLink, message);
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
