// Session: firmware detection, checks before sending, replies and waits; the board model it keeps
// is session_model.cpp.
#include "hmc/session.h"

#include <algorithm>

#include "hmc/codec.h"

namespace hmc {
namespace {

using proto::Reason;

// Longest single read while waiting, so interrupts and deadlines are seen promptly.
constexpr Millis kSlice{50};
// While a motion runs and the board says nothing for this long, ask it (an event may be lost).
constexpr Millis kStatusEvery{500};
// Longest a stopped motor may brake before the host reports it as still moving.
constexpr Millis kBrakeLimit{10000};

SessionError make_error(SessionError::Kind kind, std::string message, Reason reason = Reason::kOk) {
  SessionError e;
  e.kind = kind;
  e.message = std::move(message);
  e.reason = reason;
  return e;
}

}  // namespace

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
                          std::to_string(session->options_.reply_timeout.count()) +
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
    // VER waits as long as any reply: silence is an error now, never a guess that saves time.
    const Clock::time_point deadline = Clock::now() + options_.reply_timeout;
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

SessionResult<StepBudgets> Session::step_budgets() const {
  if (SessionResult<Done> ok = require(proto::Feature::kStepBudgets); !ok) return ok.error();
  return StepBudgets{version_->max_rate, version_->max_ramping_rate.value_or(version_->max_rate)};
}

StepBudgets Session::step_budgets_in_force() const {
  // Boards of protocols 2-6 report only max_rate; all of them ramped within 40 000 steps/s.
  constexpr uint32_t kRampingBudgetBefore7 = 40000;
  if (SessionResult<StepBudgets> reported = step_budgets()) return reported.value();
  if (firmware_ != Firmware::kV2 || !version_) return StepBudgets{};
  return StepBudgets{version_->max_rate, std::min(version_->max_rate, kRampingBudgetBefore7)};
}

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
    SessionError refused = make_error(SessionError::Kind::kNak,
                                      reason == Reason::kRateLimit && move != nullptr
                                          ? explain_rate_limit(*move)
                                          : explain_refusal(reason, &command, model_),
                                      reason);
    refused.nak = *nak;
    return refused;
  }
  return reply;
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
    SessionError refused = make_error(SessionError::Kind::kNak,
                                      (reason == Reason::kRateLimit && move != nullptr
                                           ? explain_rate_limit(*move)
                                           : explain_refusal(reason, decoded ? &decoded->command : nullptr, model_)) +
                                          " (token " + std::to_string(nak->token) + ", byte " +
                                          std::to_string(nak->offset) + ")",
                                      nak->reason);
    refused.nak = *nak;
    return refused;
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

}  // namespace hmc
