// Session: a conversation with one board over a Transport, and what the host knows of the board.
//
// open() asks `VER` and so learns whether the board runs our firmware (protocol v2: it answers
// every line and reports events) or the seed's, which answers nothing. With v2 the model of the
// board (each motor's state, position, target, microstep, rate; switches; servos; strips;
// emergency stop) comes from the board's replies and events; with the seed firmware it comes
// from what this session sent and the time each move must take.
//
// Every command is checked before it is sent — the protocol's ranges, then the board's rules
// against the model (a move toward a pressed switch, homing while a motor moves, anything but
// stop and LED while the emergency switch is pressed, servo and LED while a stepper runs under
// the seed's rules) — and a refusal, the host's or the board's, is explained in words. Replies
// are awaited with a timeout, and silence from a board that answered before is an error.
//
// A session never leaves a motor running because the host gave up: when the interrupt callback
// fires (Ctrl-C) or the link fails while it waits for a motion, it sends a stop to every motor.
// For what the host cannot catch (SIGKILL, a crash, a cut cable), arm_watchdog() arms the board's
// link watchdog (protocol 3): a background thread then keeps the link alive with a blank line
// whenever nothing else was sent for a quarter of the timeout, and the destructor disarms it.
//
// Features newer than protocol 2 are asked for with supports()/require() (proto::kFeatures); an
// older board gets kTooOld, "the board's firmware is too old for this: reflash", never a
// refusal or a frame the host cannot read.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/command.h"
#include "hmc/line_splitter.h"
#include "hmc/result.h"
#include "hmc/transport.h"

namespace hmc {

using Clock = std::chrono::steady_clock;
using Millis = std::chrono::milliseconds;

enum class Firmware : uint8_t { kV2, kSeed };

// Seed firmware: a move's end is known only from its steps and delay; the host takes it as over
// this much later (the board's clock may run a little slow, and its line takes time to arrive).
inline constexpr double kSeedTimeMargin = 1.02;
inline constexpr Millis kSeedTimeSlack{30};

// Which firmware to expect: ask VER (kDetect and kV2: no answer is a kNoReply error, as a wrong
// port or an unpowered board is silent too), or take the seed's as given (skips the query).
enum class FirmwareChoice : uint8_t { kDetect, kV2, kSeed };

struct SessionError {
  enum class Kind : uint8_t {
    kInvalid,      // the command breaks the protocol's ranges (the codec's verdict)
    kRefused,      // the host refused it: the board's rules, judged on the model
    kNak,          // the board refused it
    kNoReply,      // the board stopped answering
    kLink,         // the port failed or the connection was lost
    kInterrupted,  // interrupted (Ctrl-C); every motor was sent a stop
    kTooOld,       // the board's firmware predates a feature asked for: reflash
    kEnded,        // a motion ended early: a switch, the emergency switch, a stop, homing without its switch
  };
  Kind kind = Kind::kLink;
  std::string message;                        // in words, with what to do
  proto::Reason reason = proto::Reason::kOk;  // kInvalid, kRefused, kNak
  std::optional<Nak> nak{};                   // kNak: the board's refusal as sent (token, byte offset)
};

template <typename T>
using SessionResult = Result<T, SessionError>;

// What the host knows of the board.
struct BoardModel {
  std::array<MotorStatus, proto::kMotorCount> motors{};
  BoardStatus board{};
  std::array<StripStatus, proto::kStripCount> strips{};
  // v2: everything above came from the board. Seed: positions count from where this session
  // started, the rest is what it sent.
  bool reported = false;
  // How each motor's last motion ended (v2: from EVD), until the next one starts.
  std::array<std::optional<MotionEnd>, proto::kMotorCount> last_end{};
  // The link watchdog (STA 7), when the board has one (protocol 3).
  std::optional<WatchdogStatus> watchdog;
  // Why the board last reset (protocol 4: STR to STA 8 when the session opened, EVR when it
  // reboots); nothing from a board that predates it.
  std::optional<ResetInfo> last_reset;

  BoardModel();
  const MotorStatus& motor(uint32_t m) const { return motors[m - 1]; }
  MotorStatus& motor(uint32_t m) { return motors[m - 1]; }
  bool any_moving() const;
};

struct SessionOptions {
  FirmwareChoice firmware = FirmwareChoice::kDetect;
  Millis reply_timeout{1000};  // longest wait for one reply
  uint32_t baud = kDefaultBaud;  // the line's speed: the seed firmware is paced by it
  // Polled while waiting; returning true interrupts the wait and stops every motor.
  std::function<bool()> interrupted;
  // Every line the board sends, decoded or not, as it arrives (monitor, --verbose).
  std::function<void(std::string_view line, const Result<BoardFrame, Diagnostic>& frame)> on_line;
  // Every line the host sends, as sent (--verbose).
  std::function<void(std::string_view line)> on_send;
};

class Session {
 public:
  // Connects over an open transport and learns which firmware the board runs; with v2 it also
  // reads the board's state (STA for every unit).
  static SessionResult<std::unique_ptr<Session>> open(std::unique_ptr<Transport> transport,
                                                      const SessionOptions& options);
  // Disarms the link watchdog if this session armed it.
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // Whether the board's protocol has `feature` (never for the seed firmware).
  bool supports(proto::Feature feature) const;
  // Done, or a kTooOld error naming the feature, the protocol that brought it and the board's.
  SessionResult<Done> require(proto::Feature feature) const;
  // Arms the board's link watchdog with `timeout` (at most proto::kWatchdogMaxMs) and keeps the
  // link alive from a background thread until disarm_watchdog() or the session's end.
  SessionResult<Done> arm_watchdog(Millis timeout);
  SessionResult<Done> disarm_watchdog();
  bool watchdog_armed() const { return keep_alive_.joinable(); }
  // The board is the in-process simulator (sim://): its time stops when this process does.
  bool simulated() const { return transport_->simulated(); }

  Firmware firmware() const { return firmware_; }
  // The board's VER answer (v2 only).
  const std::optional<Version>& version() const { return version_; }
  const BoardModel& model() const { return model_; }
  // "simulated board sim://default (real time), firmware 1.0.0, protocol 2" and the like.
  std::string description() const;
  // Both step-rate budgets as the board reports them (protocol 7, proto::Feature::kStepBudgets),
  // or kTooOld.
  SessionResult<StepBudgets> step_budgets() const;
  // The budgets moves are checked against: the board's from protocol 7; before it VER's max_rate
  // and the ramping budget every firmware of those protocols had; for the seed this firmware's.
  StepBudgets step_budgets_in_force() const;
  bool legacy_rules() const;

  // Checks a command against the protocol and the model without sending it.
  SessionResult<Done> check(const Command& command) const;
  // Checks, sends, and (v2) waits for the reply: Ack, or the query's answer. A refusal is an
  // error of kind kNak, explained. Seed firmware: returns Ack once the line is sent.
  SessionResult<BoardFrame> execute(const Command& command);
  // Sends one line as given (a line end added when it has none) and waits for its reply (v2).
  // The host checks nothing: this is how a refusal by the board is tested.
  SessionResult<BoardFrame> send_line(std::string_view line);
  // Reads the board's state again (v2; a no-op for the seed).
  SessionResult<Done> refresh();
  // Waits until every motor in `motors` rests: v2 from its events, checking with STA during a
  // silence; seed from the time its move must take. nullopt limit: as long as they move.
  SessionResult<Done> wait_until_idle(const std::vector<uint32_t>& motors, std::optional<Millis> limit = {});
  // Reads and handles what the board sends until `done()` holds (checked after every read, at
  // least every 50 ms): the general wait behind wait_until_idle, with the same interrupt, link
  // and silence handling. `done` may send commands through this session.
  SessionResult<Done> wait(const std::function<bool()>& done, std::optional<Millis> limit = {});
  // Sends a stop to every motor (and, v2, waits for the replies and until they rest).
  SessionResult<Done> stop_all();
  // The same for some motors.
  SessionResult<Done> stop(const std::vector<uint32_t>& motors);
  // Reads and handles what the board sends for `duration`, or until interrupted.
  SessionResult<Done> listen(Millis duration);

  // Sends many commands as fast as the link allows and matches the replies in order. With our
  // firmware, lines go out while earlier ones are still unanswered, as long as the unanswered
  // bytes fit the board's line buffer (VER's line_max: the board's receive ring is larger, so
  // it can never overflow) — the link never waits for a reply. The commands are checked
  // against the protocol's ranges before anything is sent; the board's rules are the board's to
  // apply while streaming. At the first refusal nothing more is sent, the lines already on
  // their way are answered and counted, every motor the stream had started is stopped (giving up
  // never leaves one running), and the report says which lines were refused and why.
  // With the seed firmware, one line at a time, each after the previous one's wire time.
  struct StreamReport {
    size_t sent = 0;       // lines written
    size_t accepted = 0;   // lines the board accepted (seed: lines sent)
    std::optional<size_t> refused;  // index of the first refused command
    std::string why;       // its refusal, explained
    std::vector<size_t> refused_after;  // lines sent after it that the board refused too
    std::vector<std::string> why_after;  // why, for each of refused_after
    std::vector<uint32_t> stopped;       // after a refusal: the motors the stream had started
  };
  SessionResult<StreamReport> stream(const std::vector<Command>& commands, bool pipelined = true);

 private:
  Session(std::unique_ptr<Transport> transport, const SessionOptions& options);
  SessionResult<Done> detect();
  SessionResult<Done> detect_firmware();
  // Sends a line; `command` is what it carries, applied to the model once accepted.
  SessionResult<Done> write_line(const std::string& line, std::optional<Command> command);
  // The reply to line number `line` (lines_written_ once it was sent), handling events on the
  // way; replies to earlier lines nobody waits for any more (an interrupted stream's, a late one)
  // are passed over, never taken for its answer.
  SessionResult<BoardFrame> await_reply(std::string_view sent, uint64_t line);
  // Reads for at most `timeout`; returns frames decoded in that time (events handled).
  SessionResult<std::vector<BoardFrame>> pump(Millis timeout);
  // A rate_limit refusal of `move` in words, with the limit it broke and the numbers (the
  // board's settings and the other motors' rates, asked with GET and STA).
  std::string explain_rate_limit(const StepperMove& move);
  void apply(const BoardFrame& frame);
  void apply_sent(const Command& command);
  void settle_seed_motions();
  bool interrupted() const { return options_.interrupted && options_.interrupted(); }
  SessionError interrupted_error();
  SessionError link_error(const std::string& message);
  // Sends a stop to every motor, then gives back `error`: a wait that fails leaves nothing moving.
  SessionError stopping(SessionError error);
  void stop_keep_alive();
  void keep_alive();
  void keep_alive_if_due();  // with transport_mutex_ held

  // Seed firmware: the move each motor was last sent, timed from when it was sent.
  struct SeedMove {
    Clock::time_point start, end;
    int64_t delay_us = 1;
    int64_t sign = 1;
  };

  std::unique_ptr<Transport> transport_;
  SessionOptions options_;
  std::array<SeedMove, proto::kMotorCount> seed_moves_{};
  Firmware firmware_ = Firmware::kV2;
  std::optional<Version> version_;
  proto::ChecksumMode mode_ = proto::ChecksumMode::kSum;
  BoardModel model_;
  LineSplitter splitter_;
  struct InFlight {
    std::optional<Command> command;  // what the line carries, when it decoded
    size_t bytes = 0;                // its length on the wire, line end included
    uint64_t line = 0;               // its number: the replies come in the lines' order
  };
  std::deque<InFlight> in_flight_;  // lines sent, oldest first, awaiting replies
  size_t in_flight_bytes_ = 0;
  uint64_t lines_written_ = 0;      // lines that get a reply, sent so far
  struct Reply {
    uint64_t line = 0;  // the line it answers; 0: none was in flight (it belongs to nobody)
    BoardFrame frame;
  };
  std::deque<Reply> pending_replies_;  // replies read, not yet taken
  bool rebooted_ = false;                     // EVB seen since the last wait began
  bool detecting_ = false;                    // open(): the board's checksum mode is not known yet
  // The keep-alive thread shares the transport: every read and write holds this.
  std::mutex transport_mutex_;
  Clock::time_point last_write_{};  // guarded by transport_mutex_
  Millis keep_alive_period_{0};     // guarded by transport_mutex_; 0: the watchdog is not armed
  std::thread keep_alive_;
  std::mutex keep_alive_mutex_;
  std::condition_variable keep_alive_wake_;
  bool keep_alive_stop_ = false;  // guarded by keep_alive_mutex_
};

// The board's refusal in words, with what to do: "motor 1's switch at the forward end is pressed:
// move it the other way (or home it)".
std::string explain_refusal(proto::Reason reason, const Command* command, const BoardModel& model);

// Why a homing that ended without its switch did: "the emergency switch stopped it" or "the
// switch was not found".
std::string not_homed_cause(const BoardModel& model);

// A motor's position in full steps, for people: 819200 (1/256 step) -> "3200", 64 -> "0.25".
std::string steps_text(int64_t position);

}  // namespace hmc
