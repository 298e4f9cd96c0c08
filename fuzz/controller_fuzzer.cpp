// Fuzzes the whole board: the firmware core on the simulated board (SimBoard), driven by a
// little program the input encodes. Byte 0 picks the options (legacy, replies, baud), bytes 1-2
// each motor's acceleration; then each operation is an opcode byte (modulo 16) and its arguments:
//   0-9 (protocol v1): raw bytes, a well-formed STM / SVM / LED frame (values mostly valid,
//   checksum computed, sometimes broken), advance time, force a limit switch, emergency on/off,
//   run until idle; 10-15 (protocol v2): VER or GET, STA (units 0-7), SET (valid and invalid
//   values per setting), LIM (ranges around the axis), VER or, rarely, CRC (either mode).
// Frames are written in the checksum mode the program believes in force (the mode of the last
// CRC frame sent intact, back to the board's when one was refused).
// Virtual time, bytes sent and simulated events are capped so a run stays short.
// HMC_FUZZ_TRACE=1 writes the board's JSON-lines trace (sim_board.h) to stderr, to follow a
// reproducer: HMC_FUZZ_TRACE=1 build/fuzz/fuzz/controller_fuzzer REPRODUCER
//
// Every line sent is also cut by the host library (LineSplitter) and judged by decode() in the
// checksum mode in force when the board judges it (decided then, not when sent: a CRC line
// before it switches the mode once acknowledged); the differential fuzzer holds decode() to the
// firmware parser. After every event the board processes:
//   - replies on: the board's output splits into events (name starting with 'E') and replies;
//     every frame decodes with decode_board_frame() in the checksum mode in force when it was
//     written. Replies answer the lines in order, one each: a refused frame gets a NAK with the
//     host's verdict; a valid VER, STA or GET gets its answer (VER; STA for units 1-3, STB for
//     4, STL for 5-6; SET), never an ACK, echoing the unit / motor / setting, with the settings,
//     strip colours and checksum mode the harness knows; any other valid frame gets an ACK or a
//     rule refusal (11-16) that fits the command, its token and the board's state (soft_limit
//     only where soft limits were set, and then only for a move that leaves them). When the
//     board has drained its input, every line is answered. Replies off: no output at all, and
//     the controller's accepted + refused counts every line once drained;
//   - accepted moves respect a known max_rate setting and known soft limits;
//   - no axis moves while the emergency switch is pressed; no motor 1-2 steps toward a limit
//     switch that was already pressed (the step that closes it is allowed; homing's pull-off
//     and slow locate are moves like any other here);
//   - the controller's position and the physical axis move together (homing zeroes aside);
//   - servo pulses are 0 or 544..2400 µs and follow the last accepted SVM; LED strips show the
//     last accepted LED frame;
//   - the step scheduler never clamps an edge.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "core/controller.h"
#include "core/hal.h"
#include "fuzz_support.h"
#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/line_splitter.h"
#include "sim_board.h"

namespace {

namespace proto = hmc::proto;
using hmc::fuzz::require;
using hmc::sim::Force;
using hmc::sim::SimBoard;
using hmc::sim::Ticks;

constexpr Ticks kUs = hmc::hal::kTicksPerMicrosecond;
constexpr Ticks kMs = 1000 * kUs;
constexpr Ticks kTimeBudget = 2000 * kMs;  // virtual time per run
constexpr std::size_t kByteBudget = 2048;  // bytes sent per run
constexpr std::size_t kEventBudget = 200000;  // simulated event steps per run
constexpr uint32_t kBaud = 115200;
constexpr uint8_t kMotors = proto::kMotorCount;

// Per-motor accelerations, steps/s²: constant rate weighs most, then a spread up to beyond
// what the planner accepts.
constexpr uint32_t kAccels[] = {0, 0, 0, 500, 8000, 100000, 2000000, 3000000000u};
constexpr uint64_t kMicrosteps[] = {0, 1, 2, 4, 8, 16, 16, 16, 32, 64, 128, 256, 3, 512};
constexpr uint64_t kSteps[] = {0, 1, 2, 5, 10, 50, 100, 200, 1000, 1600, 10000, 100000, 2147483647u, 2147483648u};
constexpr uint64_t kDelays[] = {0, 1, 4, 5, 6, 20, 50, 100, 100, 250, 500, 1000, 3000, 10000, 1000000,
                                89000000, 90000000, 2147483647u};
constexpr Ticks kAdvanceUnits[] = {10 * kUs, 100 * kUs, kMs, 10 * kMs};

template <typename T, std::size_t N>
constexpr T pick(const T (&table)[N], uint8_t byte) {
  return table[byte % N];
}

// The fuzz input read front to back; zeros once it runs out.
class Reader {
 public:
  Reader(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::string bytes(std::size_t n) {
    n = std::min(n, size_ - std::min(pos_, size_));
    std::string out(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return out;
  }

 private:
  const uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

// The checksum field as the codec writes it in CRC-16 mode: `width` digits, zero-padded when
// `padded` (learnt from encode(), so the fuzzer follows the codec's format).
struct CrcFormat {
  bool padded = false;
  std::size_t width = 0;
};

const CrcFormat& crc_format() {
  static const CrcFormat format = [] {
    CrcFormat f;
    for (uint32_t r = 0; r < 256; ++r) {
      const auto text = hmc::encode(hmc::LedColor{1, r, 0, 0, 0}, proto::ChecksumMode::kCrc16);
      if (!text) continue;
      const std::size_t end = text->rfind("#ETX");
      const std::size_t begin = text->rfind('#', end - 1) + 1;
      const std::string head = text->substr(0, begin);
      const uint16_t crc = proto::crc16(reinterpret_cast<const uint8_t*>(head.data()),
                                        static_cast<uint32_t>(head.size()));
      if (crc >= 10000) continue;
      f.width = end - begin;
      f.padded = f.width > std::to_string(crc).size();
      break;
    }
    return f;
  }();
  return format;
}

std::string checksum_text(uint32_t value, proto::ChecksumMode mode) {
  std::string digits = std::to_string(value);
  if (mode == proto::ChecksumMode::kCrc16 && crc_format().padded && digits.size() < crc_format().width) {
    digits.insert(0, crc_format().width - digits.size(), '0');
  }
  return digits;
}

// A frame for `name` and `values` in checksum mode `mode`, with the checksum (or a wrong one)
// and the line end the modifier byte picks: bits 0-1 the terminator (LF, CRLF, CR, none: the
// line goes on into the next operation), bits 2-4 all set break the checksum, bit 5 a leading
// blank. The values need not be valid: the checksum is computed here, not by encode().
std::string frame(const char* name, const uint64_t* values, uint32_t count, uint8_t mod,
                  proto::ChecksumMode mode) {
  uint64_t sum = 0;
  std::string out = (mod & 0x20) != 0 ? ((mod & 0x40) != 0 ? "\t" : " ") : "";
  std::string body = "STX#" + std::to_string(count + 1) + "#" + name;
  for (uint32_t i = 0; i < count; ++i) {
    body += "#" + std::to_string(values[i]);
    sum += values[i];
  }
  body += "#";
  uint32_t checksum = static_cast<uint32_t>(sum % 256);
  uint32_t modulus = 256;
  if (mode == proto::ChecksumMode::kCrc16) {
    checksum = proto::crc16(reinterpret_cast<const uint8_t*>(body.data()), static_cast<uint32_t>(body.size()));
    modulus = 65536;
  }
  if ((mod & 0x1C) == 0x1C) checksum = (checksum + 1) % modulus;
  out += body + checksum_text(checksum, mode) + "#ETX";
  static constexpr const char* kEnds[] = {"\n", "\r\n", "\r", ""};
  return out + kEnds[mod & 3];
}

// The byte offset of token `token` in a line (leading blanks counted), as replies give it.
std::size_t token_offset(std::string_view line, uint8_t token) {
  std::size_t pos = line.find_first_not_of(" \t");
  for (uint8_t i = 0; i < token && pos != std::string_view::npos; ++i) {
    pos = line.find('#', pos);
    if (pos != std::string_view::npos) ++pos;
  }
  return pos;
}

// A complete line sent, with the host's verdict on it, decided when the board judges the line
// (the checksum mode in force then).
struct SentLine {
  std::string text;
  bool valid = false;
  hmc::fuzz::Values command;  // valid only
  hmc::Diagnostic diagnostic;  // refused only
};

bool is_query(proto::CommandId id) {
  return id == proto::CommandId::kVersion || id == proto::CommandId::kStatus || id == proto::CommandId::kGet;
}

// Commands no rule refuses: valid means accepted.
bool never_refused(proto::CommandId id) {
  return id != proto::CommandId::kStepper && id != proto::CommandId::kServo && id != proto::CommandId::kLed;
}

// Soft limits of a motor as the harness knows them.
struct Soft {
  bool on = false;
  int64_t low = 0, high = 0;
};

// The board's state that the checks compare across one step of the simulation.
struct Snapshot {
  std::array<int32_t, kMotors> axis{};
  std::array<int32_t, kMotors> position{};
  std::array<std::array<bool, 2>, kMotors> pressed{};
  std::array<bool, kMotors> running{};
  std::array<uint16_t, 2> servo_last{};
  bool emergency = false;
  uint32_t judged = 0;  // lines accepted + refused
  uint32_t accepted = 0;
};

// A switch an injected event forces at its very start, and its state then (motor 0: none).
struct Forced {
  uint8_t motor = 0;
  uint8_t end = 0;
  bool pressed = false;
};

class Harness {
 public:
  Harness(const hmc::sim::SimConfig& config, std::string_view input)
      : board_(config), axes_(config.axes), input_(input), replies_(config.options.replies), legacy_(config.options.legacy) {
    if (config.baud != 0) byte_ticks_ = (uint64_t{10} * hmc::hal::kTicksPerSecond + config.baud - 1) / config.baud;
    static const bool trace = std::getenv("HMC_FUZZ_TRACE") != nullptr;
    if (trace) board_.set_trace(&std::cerr);
    board_.boot();
    servo_[0] = servo_[1] = Expect<uint16_t>{true, hmc::fw::servo_pulse_us(90)};
    leds_[0] = leds_[1] = Expect<std::array<uint8_t, 4>>{true, {0, 0, 0, 0}};
    for (uint8_t m = 1; m <= kMotors; ++m) {
      for (uint8_t id = 1; id <= proto::kSettingCount; ++id) {
        settings_[m - 1][id - 1] = {true, board_.controller().setting(m, id)};
      }
      soft_[m - 1] = {true, Soft{}};
    }
    last_ = snapshot();
    quick_ = quick();
    check_state();
  }

  bool out_of_budget() const {
    return board_.now() >= kTimeBudget || events_ >= kEventBudget || sent_ >= kByteBudget;
  }

  void send(const std::string& bytes) {
    const std::string capped = bytes.substr(0, kByteBudget - std::min(sent_, kByteBudget));
    if (capped.empty()) return;
    sent_ += capped.size();
    board_.send(capped);
    wire_free_at_ = std::max(wire_free_at_, board_.now()) + capped.size() * byte_ticks_;
    splitter_.feed(capped);
    while (auto line = splitter_.next()) {
      SentLine sent;
      sent.text = line->text;
      pending_.push_back(std::move(sent));  // judged by the host when the board judges it
      ++lines_sent_;
    }
    // Bytes arrive on the next step: frames sent back to back may reach one main-loop pass.
    unprocessed_ = true;
  }

  // Runs the board until `target`, one event at a time while anything moves or arrives.
  void advance_to(Ticks target) {
    do {
      if (events_ >= kEventBudget) return;
      ++events_;
      run_until(board_.busy() ? std::min(board_.next_event(), target) : target);
    } while (board_.now() < target);
  }

  // Runs until nothing moves or arrives, at most `limit` longer.
  void drain(Ticks limit) {
    const Ticks end = board_.now() + limit;
    while (board_.busy() && board_.now() < end && events_ < kEventBudget) {
      ++events_;
      run_until(std::min(board_.next_event(), end));
    }
  }

  void force_limit(uint8_t motor, uint8_t end, Force force) {
    flush();
    forced_[motor - 1][end] = force;
    // The switch as the force leaves it, before anything moves.
    const hmc::sim::AxisConfig& axis = axes_[motor - 1];
    const int32_t at = last_.axis[motor - 1];
    const bool natural = axis.has_switches && (end == 0 ? at <= axis.low_switch : at >= axis.high_switch);
    const bool pressed = force == Force::kNone ? natural : force == Force::kPressed;
    step([&] { board_.force_limit(motor, end, force); }, Forced{motor, end, pressed});
  }

  void set_emergency(bool pressed) {
    flush();
    step([&] { board_.set_emergency(pressed); });
  }

  // The checks that need the input drained: every line judged (and, replies on, answered).
  void check_drained() {
    if (unprocessed_ || board_.now() < wire_free_at_ || events_ >= kEventBudget) return;
    const uint32_t judged = board_.controller().lines_accepted() + board_.controller().lines_refused();
    require(judged == lines_sent_,
            [&] {
              return "input drained, but the controller judged " + std::to_string(judged) + " of " +
                     std::to_string(lines_sent_) + " lines";
            },
            input_);
    if (replies_) {
      require(pending_.empty(),
              [&] {
                return "input drained, but " + std::to_string(pending_.size()) + " of " +
                       std::to_string(lines_sent_) + " lines got no reply; first: \"" +
                       hmc::fuzz::escape(pending_.front().text) + "\"";
              },
              input_);
    }
  }

  Ticks now() const { return board_.now(); }
  Ticks wire_free_at() const { return wire_free_at_; }
  // The checksum mode frames are written in: the last intact CRC frame's, else the board's.
  proto::ChecksumMode mode() const { return gen_mode_; }
  void set_mode(proto::ChecksumMode mode) { gen_mode_ = mode; }

 private:
  template <typename T>
  struct Expect {
    bool known = false;
    T value{};
  };

  Snapshot snapshot() const {
    Snapshot s;
    const hmc::fw::Controller& c = board_.controller();
    for (uint8_t m = 1; m <= kMotors; ++m) {
      s.axis[m - 1] = board_.axis_position(m);
      s.position[m - 1] = c.position(m);
      s.running[m - 1] = c.scheduler().is_running(m);
      for (uint8_t end = 0; end < 2; ++end) s.pressed[m - 1][end] = board_.limit_pressed(m, end);
    }
    for (uint8_t servo = 1; servo <= 2; ++servo) s.servo_last[servo - 1] = board_.servo_last_pulse(servo);
    s.emergency = board_.emergency_pressed();
    s.judged = c.lines_accepted() + c.lines_refused();
    s.accepted = c.lines_accepted();
    return s;
  }

  // What the checks depend on that can change on its own: an axis moves only on a STEP edge,
  // a line is judged, a motion starts or ends, the controller's position is set.
  struct Quick {
    std::array<uint32_t, kMotors> steps{};
    std::array<int32_t, kMotors> position{};
    std::array<bool, kMotors> running{};
    uint32_t judged = 0;
    bool operator==(const Quick& o) const {
      return steps == o.steps && position == o.position && running == o.running && judged == o.judged;
    }
  };

  Quick quick() const {
    Quick q;
    const hmc::fw::Controller& c = board_.controller();
    for (uint8_t m = 1; m <= kMotors; ++m) {
      q.steps[m - 1] = board_.steps(m);
      q.position[m - 1] = c.position(m);
      q.running[m - 1] = c.scheduler().is_running(m);
    }
    q.judged = c.lines_accepted() + c.lines_refused();
    return q;
  }

  // Bytes sent before an injected event reach the board before it.
  void flush() {
    if (unprocessed_) run_until(board_.now());
  }

  // Runs the board to `t`; the checks run only when something they look at changed, as most
  // events are main-loop passes and falling edges.
  void run_until(Ticks t) {
    board_.run_until(t);
    unprocessed_ = false;
    const Quick q = quick();
    if (q == quick_) return;
    check_step({});
  }

  // One step of the simulation (`run`), then every check across it.
  template <typename Run>
  void step(Run&& run, Forced forced = {}) {
    run();
    check_step(forced);
  }

  // Every check across the simulation since the last one.
  void check_step(const Forced& forced) {
    const Snapshot before = last_;
    const Snapshot after = snapshot();
    check_motion(before, after, forced);
    judge_lines(before, after);
    check_state();
    last_ = after;
    quick_ = quick();
  }

  void check_motion(const Snapshot& before, const Snapshot& after, const Forced& forced) {
    for (uint8_t m = 1; m <= kMotors; ++m) {
      const int32_t moved = after.axis[m - 1] - before.axis[m - 1];
      // Emergency changes only by an injected event, which halts every motor first.
      require(!(after.emergency && moved != 0),
              [&] {
                return "motor " + std::to_string(m) + " moved " + std::to_string(moved) +
                       " (1/256 step) while the emergency switch is pressed, at t=" + std::to_string(board_.now());
              },
              input_);
      if (proto::motor_has_switches(m)) {
        for (uint8_t end = 0; end < 2; ++end) {
          const bool at_start = m == forced.motor && end == forced.end ? forced.pressed : before.pressed[m - 1][end];
          const bool held = at_start && after.pressed[m - 1][end];
          const bool toward = end == 0 ? moved < 0 : moved > 0;
          require(!(held && toward),
                  [&] {
                    return "motor " + std::to_string(m) + " moved " + std::to_string(moved) +
                           " (1/256 step) toward its pressed limit switch end " + std::to_string(end) +
                           ", at t=" + std::to_string(board_.now());
                  },
                  input_);
        }
      }
      // The scheduler's position follows the axis, except where homing sets it to 0.
      const int32_t counted = after.position[m - 1] - before.position[m - 1];
      const bool zeroed = board_.controller().homed(m) && after.position[m - 1] == 0;
      require(counted == moved || zeroed,
              [&] {
                return "motor " + std::to_string(m) + ": the controller counted " + std::to_string(counted) +
                       " (1/256 step) but the axis moved " + std::to_string(moved) + " (driver microstep " +
                       std::to_string(board_.driver_microstep(m)) + ", controller microstep " +
                       std::to_string(board_.controller().microstep(m)) + "), at t=" + std::to_string(board_.now());
              },
              input_);
    }
    for (uint8_t servo = 1; servo <= 2; ++servo) {
      require(!(after.emergency && before.emergency && after.servo_last[servo - 1] != before.servo_last[servo - 1]),
              [&] { return "servo " + std::to_string(servo) + " moved while the emergency switch is pressed"; },
              input_);
    }
  }

  // The host's verdict on the next line the board judges, in the checksum mode in force.
  SentLine& decide_front() {
    SentLine& line = pending_.front();
    const auto verdict = hmc::decode(line.text, mode_);
    line.valid = verdict.ok();
    if (verdict) {
      line.command = hmc::fuzz::values_of(verdict->command);
    } else {
      line.diagnostic = verdict.error();
    }
    return line;
  }

  // The line at the front has been judged and answered: a valid CRC switches the mode now.
  void pop_front() {
    const SentLine& line = pending_.front();
    if (line.valid && line.command.id == proto::CommandId::kChecksumMode) {
      mode_ = static_cast<proto::ChecksumMode>(line.command.v[0]);
    }
    pending_.pop_front();
    if (pending_.empty()) gen_mode_ = mode_;
  }

  // An event (EVB, EVD, ...): only its form is checked, and what it tells of the switches.
  void check_event(const hmc::BoardFrame& event, const std::string& text) {
    if (const auto* limit = std::get_if<hmc::LimitChanged>(&event)) {
      require(proto::motor_has_switches(limit->motor),
              [&] { return "event \"" + text + "\" for a motor without limit switches"; }, input_);
    }
  }

  // Matches the lines the board judged in this step to the lines sent, in order.
  void judge_lines(const Snapshot& before, const Snapshot& after) {
    // What the firmware wrote in this step, whether or not it has crossed the line yet.
    const std::string output = board_.take_written();
    const uint32_t judged = after.judged - before.judged;
    require(judged <= pending_.size(),
            [&] {
              return "the controller judged " + std::to_string(judged) + " lines, only " +
                     std::to_string(pending_.size()) + " complete lines are waiting";
            },
            input_);
    if (!replies_) {
      require(output.empty(), [&] { return "replies are off, yet the board wrote \"" + hmc::fuzz::escape(output) + "\""; },
              input_);
      judge_silent(before, after, judged);
      return;
    }
    output_ += output;
    uint32_t answered = 0;
    for (std::size_t end = output_.find('\n'); end != std::string::npos; end = output_.find('\n')) {
      const std::string text = output_.substr(0, end);
      output_.erase(0, end + 1);
      const auto frame = hmc::decode_board_frame(text, mode_);
      require(frame.ok(),
              [&] {
                return "malformed frame from the board \"" + hmc::fuzz::escape(text) + "\" (checksum mode " +
                       std::to_string(static_cast<int>(mode_)) + "): " + frame.error().message;
              },
              input_);
      require(text.find_first_of("\r\t ") == std::string::npos &&
                  hmc::encode_board_frame(*frame, mode_).ok() && *hmc::encode_board_frame(*frame, mode_) == text,
              [&] { return "frame from the board \"" + hmc::fuzz::escape(text) + "\" is not canonical"; }, input_);
      if (hmc::is_event(*frame)) {
        check_event(*frame, text);
        continue;
      }
      require(!pending_.empty(), [&] { return "reply \"" + text + "\" answers no line"; }, input_);
      ++answered;
      check_reply(decide_front(), *frame, text, before, after, judged == 1);
      pop_front();
    }
    require(answered == judged,
            [&] {
              return std::to_string(judged) + " lines judged but " + std::to_string(answered) +
                     " replies written, at t=" + std::to_string(board_.now());
            },
            input_);
    require(board_.controller().lines_accepted() == accepted_seen_,
            [&] {
              return "lines_accepted() is " + std::to_string(board_.controller().lines_accepted()) +
                     ", ACKs and query answers sent " + std::to_string(accepted_seen_);
            },
            input_);
  }

  // Replies off: the controller's counts tell how many lines were judged and how many of them
  // accepted; their effects are known when all or none of the valid ones were.
  void judge_silent(const Snapshot& before, const Snapshot& after, uint32_t judged) {
    // The verdicts, in order: a valid CRC changes the mode of the lines after it.
    std::deque<SentLine> lines;
    uint32_t valid = 0, refused_frames = 0;
    for (uint32_t i = 0; i < judged; ++i) {
      lines.push_back(decide_front());
      (lines.back().valid ? valid : refused_frames) += 1;
      pop_front();
    }
    const uint32_t accepted = after.accepted - before.accepted;
    require(accepted <= valid,
            [&] {
              return std::to_string(accepted) + " lines accepted of " + std::to_string(judged) + ", of which only " +
                     std::to_string(valid) + " are valid frames";
            },
            input_);
    for (const SentLine& line : lines) {
      if (!line.valid) continue;
      if (accepted == valid || never_refused(line.command.id)) {
        accept(line.command, before, after, judged == 1);
      } else if (accepted != 0) {
        forget(line.command);
      }
    }
  }

  void check_reply(const SentLine& line, const hmc::BoardFrame& reply, const std::string& text,
                   const Snapshot& before, const Snapshot& after, bool alone) {
    const auto context = [&] {
      return "line \"" + hmc::fuzz::escape(line.text) + "\" answered \"" + text + "\", at t=" +
             std::to_string(board_.now());
    };
    const auto* nak = std::get_if<hmc::Nak>(&reply);
    require(nak == nullptr || (nak->reason >= proto::Reason::kLineTooLong &&
                               static_cast<uint32_t>(nak->reason) < proto::kReasonCount),
            [&] { return context() + ": unknown reason"; }, input_);
    if (!line.valid) {
      const hmc::Diagnostic& d = line.diagnostic;
      const uint32_t token = d.token == hmc::kNoToken ? 255u : static_cast<uint32_t>(d.token);
      require(nak != nullptr && nak->reason == d.reason && nak->token == token && nak->offset == d.offset,
              [&] {
                return context() + "; the host refuses it: " + proto::reason_spec(d.reason).name + " token " +
                       std::to_string(token) + " offset " + std::to_string(d.offset) + " (checksum mode " +
                       std::to_string(static_cast<int>(mode_)) + ")";
              },
              input_);
      return;
    }
    const hmc::fuzz::Values& c = line.command;
    if (is_query(c.id)) {
      check_answer(c, reply, before, after, context);
      ++accepted_seen_;
      return;
    }
    if (std::holds_alternative<hmc::Ack>(reply)) {
      ++accepted_seen_;
      accept(c, before, after, alone);
      return;
    }
    require(nak != nullptr, [&] { return context() + ": expected ACK or NAK"; }, input_);
    check_rule_refusal(line, *nak, before, after, alone, context);
  }

  // The answer to a valid query: the matching frame, echoing what was asked.
  template <typename Context>
  void check_answer(const hmc::fuzz::Values& c, const hmc::BoardFrame& reply, const Snapshot& before,
                    const Snapshot& after, Context&& context) {
    const auto fail_unless = [&](bool holds, const char* why) {
      require(holds, [&] { return context() + ": " + why; }, input_);
    };
    switch (c.id) {
      case proto::CommandId::kVersion: {
        const auto* v = std::get_if<hmc::Version>(&reply);
        fail_unless(v != nullptr, "VER must be answered by VER");
        fail_unless(v->protocol == proto::kProtocolVersion && v->firmware == proto::kFirmwareVersion &&
                        v->legacy == legacy_ && v->line_max == proto::kLineMax &&
                        v->max_rate == hmc::fw::kMaxStepRate &&
                        v->max_ramping_rate == std::optional<uint32_t>(proto::kMaxRampingStepRate) &&
                        v->board == 322 && v->switch_mask == 3 && v->checksum_mode == mode_,
                    "VER does not describe this board (or the checksum mode in force)");
        break;
      }
      case proto::CommandId::kStatus: {
        const uint32_t unit = c.v[0];
        if (unit <= kMotors) {
          const auto* st = std::get_if<hmc::MotorStatus>(&reply);
          fail_unless(st != nullptr, "STA 1-3 must be answered by STA");
          fail_unless(st->motor == unit, "STA answers another motor");
        } else if (unit == proto::kUnitBoard) {
          const auto* st = std::get_if<hmc::BoardStatus>(&reply);
          fail_unless(st != nullptr, "STA 4 must be answered by STB");
          fail_unless(before.emergency != after.emergency || st->emergency == after.emergency,
                      "STB shows the wrong emergency switch state");
        } else if (unit == proto::kUnitWatchdog) {
          fail_unless(std::holds_alternative<hmc::WatchdogStatus>(reply), "STA 7 must be answered by STW");
        } else if (unit == proto::kUnitReset) {
          const auto* st = std::get_if<hmc::ResetStatus>(&reply);
          fail_unless(st != nullptr, "STA 8 must be answered by STR");
          fail_unless(st->cause == proto::ResetCause::kPowerOn && st->pc == 0, "STR: a simulated board is powered on");
        } else {
          const auto* st = std::get_if<hmc::StripStatus>(&reply);
          fail_unless(st != nullptr, "STA 5-6 must be answered by STL");
          fail_unless(st->strip == unit - proto::kUnitFirstStrip + 1, "STL answers another strip");
          const Expect<std::array<uint8_t, 4>>& led = leds_[st->strip - 1];
          fail_unless(!led.known || (st->r == led.value[0] && st->g == led.value[1] && st->b == led.value[2] &&
                                     st->w == led.value[3]),
                      "STL shows another colour than the last accepted LED frame");
        }
        break;
      }
      case proto::CommandId::kGet: {
        const auto* sv = std::get_if<hmc::SettingValue>(&reply);
        fail_unless(sv != nullptr, "GET must be answered by SET");
        fail_unless(sv->motor == c.v[0] && sv->setting == c.v[1], "SET answers another motor or setting");
        const Expect<uint32_t>& known = settings_[c.v[0] - 1][c.v[1] - 1];
        fail_unless(!known.known || sv->value == known.value, "SET shows another value than the last accepted SET");
        break;
      }
      default:
        break;
    }
  }

  // A valid frame refused by a rule (controller.h): the reason fits the command and the state.
  template <typename Context>
  void check_rule_refusal(const SentLine& line, const hmc::Nak& reply, const Snapshot& before, const Snapshot& after,
                          bool alone, Context&& context) {
    const hmc::fuzz::Values& c = line.command;
    const bool stm = c.id == proto::CommandId::kStepper;
    const uint32_t motor = c.v[0];
    const uint32_t dir = stm ? c.v[1] : 0;
    if (stm) require(motor >= 1 && motor <= kMotors, [&] { return context() + ": no such motor"; }, input_);
    const bool any_running_before_or_after =
        std::find(before.running.begin(), before.running.end(), true) != before.running.end() ||
        std::find(after.running.begin(), after.running.end(), true) != after.running.end();
    uint32_t token = 0;
    bool fits = false;
    switch (reply.reason) {
      case proto::Reason::kLimitPressed: {
        token = proto::kTokenFirstValue + 1;
        const uint8_t end = dir == proto::kActionReverse ? 0 : 1;
        fits = stm && (dir == proto::kActionForward || dir == proto::kActionReverse) &&
               proto::motor_has_switches(motor) &&
               (before.pressed[motor - 1][end] || after.pressed[motor - 1][end]);
        break;
      }
      case proto::Reason::kMotorsRunning:
        token = proto::kTokenFirstValue + 1;
        fits = stm && dir == proto::kActionHome && (!alone || any_running_before_or_after);
        break;
      case proto::Reason::kEmergencyStop:
        token = proto::kTokenName;
        fits = after.emergency && ((stm && dir != proto::kActionStop) || c.id == proto::CommandId::kServo);
        break;
      case proto::Reason::kBusy:
        token = proto::kTokenName;
        fits = legacy_ && !stm && (!alone || any_running_before_or_after);
        break;
      case proto::Reason::kRateLimit:
        // The timer's range, the budget of all moving motors or the motor's max_rate setting.
        token = proto::kTokenFirstValue + 4;
        fits = stm && dir != proto::kActionStop;
        break;
      case proto::Reason::kSoftLimit: {
        token = proto::kTokenFirstValue + 3;
        const Expect<Soft>& soft = soft_[motor - 1];
        fits = stm && (dir == proto::kActionForward || dir == proto::kActionReverse) &&
               (!soft.known || (soft.value.on && (!alone || before.running[motor - 1] ||
                                                 leaves_soft_limits(c, soft.value, before.position[motor - 1]))));
        break;
      }
      default:
        break;
    }
    require(fits, [&] { return context() + ": the refusal does not fit the frame or the board's state"; }, input_);
    require(reply.token == token && reply.offset == token_offset(line.text, static_cast<uint8_t>(token)),
            [&] {
              return context() + ": expected token " + std::to_string(token) + " at offset " +
                     std::to_string(token_offset(line.text, static_cast<uint8_t>(token)));
            },
            input_);
  }

  // An accepted frame: it must have been allowed, and its effect becomes what the board shows.
  // `alone`: the only line judged in this step, so the state before and after brackets it.
  void accept(const hmc::fuzz::Values& c, const Snapshot& before, const Snapshot& after, bool alone) {
    const auto fail_if = [&](bool wrong, const char* why) {
      require(!wrong, [&] { return "accepted " + hmc::fuzz::to_string(c) + " " + why + ", at t=" + std::to_string(board_.now()); },
              input_);
    };
    const bool running_throughout = [&] {
      for (uint8_t i = 0; i < kMotors; ++i) {
        if (before.running[i] && after.running[i]) return true;
      }
      return false;
    }();
    switch (c.id) {
      case proto::CommandId::kStepper: {
        const uint32_t motor = c.v[0], dir = c.v[1];
        if (dir == proto::kActionStop) break;
        fail_if(after.emergency, "while the emergency switch is pressed");
        if (dir == proto::kActionHome) {
          bool other_running = false;
          for (uint8_t i = 0; i < kMotors; ++i) {
            other_running = other_running || (i != motor - 1 && before.running[i] && after.running[i]);
          }
          fail_if(alone && other_running, "(homing) while another motor runs");
          break;
        }
        const Expect<uint32_t>& max_rate = settings_[motor - 1][proto::kSettingMaxRate - 1];
        const uint32_t delay = c.v[4];
        fail_if(max_rate.known && delay != 0 && (1000000u + delay - 1u) / delay > max_rate.value,
                "faster than the motor's max_rate setting");
        const Expect<Soft>& soft = soft_[motor - 1];
        fail_if(soft.known && soft.value.on && alone && !before.running[motor - 1] &&
                    leaves_soft_limits(c, soft.value, before.position[motor - 1]),
                "ending outside the motor's soft limits");
        if (!proto::motor_has_switches(motor)) break;
        const uint8_t end = dir == proto::kActionReverse ? 0 : 1;
        fail_if(forced_[motor - 1][end] == Force::kPressed, "toward a limit switch held pressed");
        fail_if(before.pressed[motor - 1][end] && after.pressed[motor - 1][end] &&
                    before.axis[motor - 1] == after.axis[motor - 1],
                "toward a pressed limit switch");
        break;
      }
      case proto::CommandId::kServo:
        fail_if(after.emergency, "while the emergency switch is pressed");
        fail_if(legacy_ && alone && running_throughout, "in legacy mode while a stepper runs");
        servo_[c.v[0] - 1] = {true, hmc::fw::servo_pulse_us(c.v[1])};
        break;
      case proto::CommandId::kLed:
        fail_if(legacy_ && alone && running_throughout, "in legacy mode while a stepper runs");
        leds_[c.v[0] - 1] = {true, {static_cast<uint8_t>(c.v[1]), static_cast<uint8_t>(c.v[2]),
                                    static_cast<uint8_t>(c.v[3]), static_cast<uint8_t>(c.v[4])}};
        break;
      case proto::CommandId::kSet:
        settings_[c.v[0] - 1][c.v[1] - 1] = {true, c.v[2]};
        break;
      case proto::CommandId::kLimits: {
        Soft soft;
        soft.low = c.v[1] != 0 ? -int64_t{c.v[2]} : int64_t{c.v[2]};
        soft.high = c.v[3] != 0 ? -int64_t{c.v[4]} : int64_t{c.v[4]};
        soft.on = soft.low < soft.high;
        soft_[c.v[0] - 1] = {true, soft};
        break;
      }
      case proto::CommandId::kVersion:
      case proto::CommandId::kStatus:
      case proto::CommandId::kGet:
      case proto::CommandId::kChecksumMode:  // the mode changes once the line is answered
      case proto::CommandId::kWatchdog:      // its stops are reported as EVD and checked as any end
      case proto::CommandId::kSetPosition:   // accepted at rest only; the position is the board's
        break;
    }
  }

  // A move (STM forward or reverse) from `here` that would end outside soft limits that are on
  // (controller_motion.cpp): a run until stopped with no room at all, or more steps than fit.
  static bool leaves_soft_limits(const hmc::fuzz::Values& c, const Soft& soft, int64_t here) {
    const int64_t units = 256 / static_cast<int64_t>(c.v[2]);
    const int64_t room = c.v[1] == proto::kActionReverse ? here - soft.low : soft.high - here;
    const int64_t most = room < 0 ? 0 : room / units;
    return c.v[3] == 0 ? most == 0 : static_cast<int64_t>(c.v[3]) > most;
  }

  // A frame that may or may not have been accepted: what it sets is no longer known.
  void forget(const hmc::fuzz::Values& c) {
    if (c.id == proto::CommandId::kServo) servo_[c.v[0] - 1].known = false;
    if (c.id == proto::CommandId::kLed) leds_[c.v[0] - 1].known = false;
    if (c.id == proto::CommandId::kSet) settings_[c.v[0] - 1][c.v[1] - 1].known = false;
    if (c.id == proto::CommandId::kLimits) soft_[c.v[0] - 1].known = false;
  }

  // Outputs that must hold at every moment.
  void check_state() {
    const uint32_t clamped = board_.controller().scheduler().clamped_edges();
    require(clamped == 0, [&] { return "the step scheduler clamped " + std::to_string(clamped) + " edges"; },
            input_);
    for (uint8_t servo = 1; servo <= 2; ++servo) {
      const uint16_t pulse = board_.servo_pulse(servo);
      const uint16_t last = board_.servo_last_pulse(servo);
      const Expect<uint16_t>& expected = servo_[servo - 1];
      require((pulse == 0 || pulse == last) && last >= 544 && last <= 2400 &&
                  (!expected.known || last == expected.value),
              [&] {
                return "servo " + std::to_string(servo) + " pulse " + std::to_string(pulse) + " us, last " +
                       std::to_string(last) + " us, expected " +
                       (expected.known ? std::to_string(expected.value) : std::string("544..2400"));
              },
              input_);
    }
    for (uint8_t strip = 1; strip <= 2; ++strip) {
      const auto shown = board_.led(strip);
      const Expect<std::array<uint8_t, 4>>& expected = leds_[strip - 1];
      require(!expected.known || shown == expected.value,
              [&] {
                auto rgbw = [](const std::array<uint8_t, 4>& v) {
                  return std::to_string(v[0]) + "," + std::to_string(v[1]) + "," + std::to_string(v[2]) + "," +
                         std::to_string(v[3]);
                };
                return "LED strip " + std::to_string(strip) + " shows " + rgbw(shown) + ", last accepted " +
                       rgbw(expected.value);
              },
              input_);
    }
  }

  SimBoard board_;
  std::array<hmc::sim::AxisConfig, kMotors> axes_;
  std::string_view input_;
  bool replies_;
  bool legacy_;
  Ticks byte_ticks_ = 0;
  Ticks wire_free_at_ = 0;
  std::size_t sent_ = 0;
  std::size_t events_ = 0;
  bool unprocessed_ = false;  // bytes sent since the board last ran
  hmc::LineSplitter splitter_;
  std::deque<SentLine> pending_;  // complete lines not yet judged
  uint32_t lines_sent_ = 0;
  uint32_t accepted_seen_ = 0;  // ACKs and query answers
  std::string output_;  // frames from the board not yet complete
  proto::ChecksumMode mode_ = proto::ChecksumMode::kSum;      // the board's, for the next line judged
  proto::ChecksumMode gen_mode_ = proto::ChecksumMode::kSum;  // frames are written in this mode
  Snapshot last_;
  Quick quick_;
  std::array<std::array<Force, 2>, kMotors> forced_{};
  std::array<Expect<uint16_t>, 2> servo_{};
  std::array<Expect<std::array<uint8_t, 4>>, 2> leds_{};
  std::array<std::array<Expect<uint32_t>, proto::kSettingCount>, kMotors> settings_{};
  std::array<Expect<Soft>, kMotors> soft_{};
};

// Positions for soft limits, 1/256 step, around the simulated axes (switches at 0 and 409 600,
// start 204 800).
constexpr int64_t kLimitPoints[] = {-409600, -256, 0, 0, 256, 51200, 102400, 200000,
                                    204800, 204800, 209600, 307200, 409600, 409600, 819200, 2147483647};

// A motor 1-3, rarely 0 or 4.
uint64_t motor_of(uint8_t b) { return b % 16 == 15 ? (b & 0x10) * 4u / 16u : 1u + b % 15 / 5; }

// A setting 1-8, rarely 0 or 9.
uint64_t setting_of(uint8_t b) { return b % 32 == 31 ? ((b & 0x20) != 0 ? 9 : 0) : 1u + b % 8; }

// A value for `setting`: its bounds, its initial value, just outside, or a useful one.
uint64_t setting_value(uint64_t setting, uint8_t b) {
  static constexpr uint64_t kUseful[proto::kSettingCount][4] = {
      {500, 1500, 2500, 4000},     // current_ma
      {0, 1, 2, 4},                // decay
      {500, 8000, 100000, 2000000},  // accel
      {100, 1000, 4000, 20000},    // max_rate
      {1, 1, 0, 1},                // home_end
      {5, 50, 200, 2000},          // home_seek_us
      {1, 16, 160, 100000},        // home_pull_off
      {100, 1000, 5000, 1000000},  // home_locate_us
  };
  if (setting < 1 || setting > proto::kSettingCount) return b;
  const proto::SettingSpec& spec = proto::kSettings[setting - 1];
  switch (b % 10) {
    case 0: return spec.min;
    case 1: return spec.max;
    case 2: return spec.initial;
    case 3: return spec.min > 0 ? spec.min - 1 : uint64_t{spec.max} + 1;  // out of range
    case 4: return (b & 0x80) != 0 ? uint64_t{spec.max} + 1 : 2147483648u;  // out of range, bad number
    default: return kUseful[setting - 1][b % 4];
  }
}

// One operation from the input.
void run_operation(Harness& h, Reader& in) {
  // Opcodes 0-9 are protocol v1's (the seeds' format before v2), 10-15 protocol v2's.
  enum Op : uint8_t {
    kRaw, kStm, kStm2, kSvm, kLed, kAdvance, kAdvance2, kLimit, kEmergency, kDrain,
    kVerGet, kSta, kSet, kSet2, kLim, kVerCrc, kOpCount
  };
  switch (static_cast<Op>(in.byte() % kOpCount)) {
    case kRaw:
      h.send(in.bytes(1u + in.byte() % 48u));
      break;
    case kStm:
    case kStm2: {
      const uint8_t m = in.byte(), d = in.byte();
      const uint64_t motor = m % 16 == 15 ? (m & 0x10) * 4u / 16u : 1u + m % 15 / 5;  // rarely 0 or 4
      const uint64_t dir = d % 32 == 31 ? 4 : d % 4;
      const uint64_t values[] = {motor, dir, pick(kMicrosteps, in.byte()), pick(kSteps, in.byte()),
                                 pick(kDelays, in.byte())};
      h.send(frame("STM", values, 5, in.byte(), h.mode()));
      break;
    }
    case kSvm: {
      const uint8_t s = in.byte(), a = in.byte();
      const uint64_t servo = s % 16 == 15 ? (s & 0x10) * 3u / 16u : 1u + s % 2;  // rarely 0 or 3
      const uint64_t angle = s & 0x20 ? a : 10u + a % 161u;  // sometimes out of range
      const uint64_t values[] = {servo, angle};
      h.send(frame("SVM", values, 2, in.byte(), h.mode()));
      break;
    }
    case kLed: {
      const uint8_t s = in.byte();
      const uint64_t strip = s % 16 == 15 ? (s & 0x10) * 3u / 16u : 1u + s % 2;  // rarely 0 or 3
      uint64_t values[] = {strip, in.byte(), in.byte(), in.byte(), in.byte()};
      if ((s & 0xE0) == 0xE0) values[1] += 256;  // out of range
      h.send(frame("LED", values, 5, in.byte(), h.mode()));
      break;
    }
    case kAdvance:
    case kAdvance2: {
      const uint8_t b = in.byte();
      h.advance_to(std::min(h.now() + kAdvanceUnits[b >> 6] * (b % 64u + 1u), kTimeBudget));
      break;
    }
    case kLimit: {
      const uint8_t b = in.byte();
      const auto motor = static_cast<uint8_t>(1 + (b & 3) % 3);
      const auto end = static_cast<uint8_t>((b >> 2) & 1);
      static constexpr Force kForces[] = {Force::kPressed, Force::kReleased, Force::kNone};
      h.force_limit(motor, end, kForces[(b >> 3) % 3]);
      break;
    }
    case kEmergency:
      h.set_emergency((in.byte() & 1) != 0);
      break;
    case kDrain:
      h.drain(std::min<Ticks>(500 * kMs, kTimeBudget - std::min(h.now(), kTimeBudget)));
      break;
    case kVerGet: {
      const uint8_t b = in.byte();
      if ((b & 1) != 0) {
        h.send(frame("VER", nullptr, 0, in.byte(), h.mode()));
        break;
      }
      const uint64_t values[] = {motor_of(b >> 1), setting_of(in.byte())};
      h.send(frame("GET", values, 2, in.byte(), h.mode()));
      break;
    }
    case kSta: {
      const uint64_t unit = in.byte() % 8;  // 0 and 7 out of range
      h.send(frame("STA", &unit, 1, in.byte(), h.mode()));
      break;
    }
    case kSet:
    case kSet2: {
      const uint64_t motor = motor_of(in.byte()), setting = setting_of(in.byte());
      const uint64_t values[] = {motor, setting, setting_value(setting, in.byte())};
      h.send(frame("SET", values, 3, in.byte(), h.mode()));
      break;
    }
    case kLim: {
      const uint64_t motor = motor_of(in.byte());
      const uint8_t range = in.byte();
      int64_t low = pick(kLimitPoints, static_cast<uint8_t>(range & 0x0F));
      int64_t high = pick(kLimitPoints, static_cast<uint8_t>(range >> 4));
      if (range == 0xFF) low = high = 0;  // off
      const uint64_t values[] = {motor, low < 0 ? 1u : 0u, static_cast<uint64_t>(low < 0 ? -low : low),
                                 high < 0 ? 1u : 0u, static_cast<uint64_t>(high < 0 ? -high : high)};
      h.send(frame("LIM", values, 5, in.byte(), h.mode()));
      break;
    }
    case kVerCrc: {
      const uint8_t b = in.byte(), mod = in.byte();
      if (b % 4 != 0) {  // CRC rarely
        h.send(frame("VER", nullptr, 0, mod, h.mode()));
        break;
      }
      const uint64_t mode = (b >> 2) % 8 == 7 ? 2 : (b >> 2) & 1;  // rarely out of range
      const std::string line = frame("CRC", &mode, 1, mod, h.mode());
      // An intact CRC frame switches the mode of the frames written after it.
      if (mode <= 1 && (mod & 0x1C) != 0x1C) h.set_mode(static_cast<proto::ChecksumMode>(mode));
      h.send(line);
      break;
    }
    case kOpCount:
      break;
  }
  h.check_drained();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  Reader in(data, size);
  const uint8_t options = in.byte();
  const uint8_t accel12 = in.byte();
  const uint8_t accel3 = in.byte();

  hmc::sim::SimConfig config;
  config.options.self_test = false;
  config.options.legacy = (options & 1) != 0;
  config.options.replies = (options & 2) == 0;
  config.baud = (options & 4) != 0 ? kBaud : 0;
  config.accel = {pick(kAccels, accel12), pick(kAccels, static_cast<uint8_t>(accel12 >> 4)), pick(kAccels, accel3)};

  Harness h(config, hmc::fuzz::as_text(data, size));
  while (!in.empty() && !h.out_of_budget()) run_operation(h, in);
  // Let what is on the wire arrive, then every line must have been judged.
  h.advance_to(std::max(h.now(), h.wire_free_at()));
  h.check_drained();
  return 0;
}
