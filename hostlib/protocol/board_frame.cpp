// Board -> host frames: decoding with the shared grammar (frame_grammar.h) against
// proto::kBoardFrames, the typed forms, encoding, and descriptions in words.
//
// Each typed frame lists its wire fields once, in fields() below; reading values into the type
// and writing the type back to values both walk that one list.
#include "hmc/board_frame.h"

#include <array>
#include <optional>
#include <type_traits>
#include <utility>

#include "frame_grammar.h"

namespace hmc {
namespace {

namespace g = grammar;

// The field lists: plain numbers, flags (0/1), codes (enums), signed positions (sign and
// magnitude, two values), STA's packed flags, and numbers a later protocol added at the end
// (absent from an older board's frame: its shape's `older` form).
template <typename IO> constexpr void fields(IO&, Ack&) {}
template <typename IO> constexpr void fields(IO& io, Nak& f) {
  io.code(f.reason); io.number(f.token); io.number(f.offset);
}
template <typename IO> constexpr void fields(IO& io, Version& f) {
  io.number(f.protocol); io.number(f.firmware); io.flag(f.legacy); io.number(f.line_max); io.number(f.max_rate);
  io.number(f.board); io.number(f.switch_mask); io.code(f.checksum_mode); io.later(f.max_ramping_rate);
}
template <typename IO> constexpr void fields(IO& io, MotorStatus& f) {
  io.number(f.motor); io.code(f.state); io.position(f.position); io.position(f.target); io.number(f.rate);
  io.motor_flags(f);
}
template <typename IO> constexpr void fields(IO& io, BoardStatus& f) {
  io.flag(f.emergency); io.number(f.limits); io.number(f.servo1_us); io.number(f.servo2_us);
}
template <typename IO> constexpr void fields(IO& io, StripStatus& f) {
  io.number(f.strip); io.number(f.r); io.number(f.g); io.number(f.b); io.number(f.w);
}
template <typename IO> constexpr void fields(IO& io, SettingValue& f) {
  io.number(f.motor); io.number(f.setting); io.number(f.value);
}
template <typename IO> constexpr void fields(IO& io, Booted& f) { io.number(f.protocol); io.number(f.firmware); }
template <typename IO> constexpr void fields(IO& io, MotionEnded& f) {
  io.number(f.motor); io.code(f.how); io.position(f.position);
}
template <typename IO> constexpr void fields(IO& io, HomingEnded& f) {
  io.number(f.motor); io.flag(f.homed); io.position(f.position);
}
template <typename IO> constexpr void fields(IO& io, LimitChanged& f) {
  io.number(f.motor); io.number(f.end); io.flag(f.pressed);
}
template <typename IO> constexpr void fields(IO& io, EmergencyChanged& f) { io.flag(f.pressed); }
template <typename IO> constexpr void fields(IO& io, DriverFault& f) { io.number(f.motor); io.number(f.status); }
template <typename IO> constexpr void fields(IO& io, WatchdogStatus& f) { io.number(f.timeout_ms); io.flag(f.fired); }
template <typename IO> constexpr void fields(IO& io, ResetInfo& f) {
  io.code(f.cause); io.number(f.exception); io.number(f.pc); io.number(f.lr); io.number(f.context);
}

// STA's flags: bit 0 homed, bits 1-2 the switches, bit 3 runs until stopped, bits 4-7 log2
// microstep.
constexpr uint32_t kFlagHomed = 1u << 0;
constexpr uint32_t kFlagSwitchShift = 1;
constexpr uint32_t kFlagEndless = 1u << 3;
constexpr uint32_t kFlagMicrostepShift = 4;
constexpr uint32_t kMaxLog2Microstep = 15;  // four bits

// Counts the values a field list has, for the check against the table below.
struct Counter {
  uint32_t count = 0;
  template <typename T> constexpr void number(T&) { ++count; }
  template <typename T> constexpr void flag(T&) { ++count; }
  template <typename T> constexpr void code(T&) { ++count; }
  template <typename T> constexpr void position(T&) { count += 2; }
  template <typename T> constexpr void motor_flags(T&) { ++count; }
  template <typename T> constexpr void later(T&) { ++count; }
};

template <typename T>
constexpr uint32_t value_count_of() {
  T frame{};
  Counter counter;
  fields(counter, frame);
  return counter.count;
}

template <std::size_t... I>
constexpr bool variant_follows_table(std::index_sequence<I...>) {
  return ((proto::kBoardFrames[I].id == static_cast<proto::BoardFrameId>(I) &&
           value_count_of<std::variant_alternative_t<I, BoardFrame>>() == proto::kBoardFrames[I].value_count) &&
          ...);
}
static_assert(std::variant_size_v<BoardFrame> == proto::kBoardFrameCount, "one BoardFrame alternative per frame");
static_assert(variant_follows_table(std::make_index_sequence<std::variant_size_v<BoardFrame>>{}),
              "BoardFrame's alternatives are ordered by BoardFrameId and hold the table's values");
static_assert(proto::kMotorStatusFields[1].max == static_cast<uint32_t>(MotorState::kSelfTest) &&
                  proto::kMotionEndedFields[1].min == static_cast<uint32_t>(MotionEnd::kCompleted) &&
                  proto::kMotionEndedFields[1].max == static_cast<uint32_t>(MotionEnd::kWatchdog),
              "the enums span their fields' ranges");

// Values (already range-checked) into a typed frame.
class Reader {
 public:
  Reader(const uint32_t* values, uint32_t count) : values_(values), count_(count) {}
  void number(uint32_t& x) { x = next(); }
  void flag(bool& x) { x = next() != 0; }
  template <typename E> void code(E& x) { x = static_cast<E>(next()); }
  void position(int64_t& x) {
    const bool minus = next() != 0;
    const int64_t magnitude = next();
    x = minus ? -magnitude : magnitude;
  }
  void motor_flags(MotorStatus& s) {
    const uint32_t flags = next();
    s.homed = (flags & kFlagHomed) != 0;
    s.switches = (flags >> kFlagSwitchShift) & 3u;
    s.endless = (flags & kFlagEndless) != 0;
    s.microstep = 1u << ((flags >> kFlagMicrostepShift) & 0xFu);
  }
  void later(std::optional<uint32_t>& x) { x = at_ < count_ ? std::optional<uint32_t>(next()) : std::nullopt; }

 private:
  uint32_t next() { return values_[at_++]; }
  const uint32_t* values_;
  uint32_t count_;
  std::size_t at_ = 0;
};

// A typed frame into values; notes the first field the wire cannot carry.
class Writer {
 public:
  struct Problem {
    uint32_t field;
    uint32_t found;
    std::string message;
  };

  void number(const uint32_t& x) { add(x); }
  void flag(const bool& x) { add(x ? 1u : 0u); }
  template <typename E> void code(const E& x) { add(static_cast<uint32_t>(x)); }
  void position(const int64_t& x) {
    const uint64_t magnitude = x < 0 ? 0u - static_cast<uint64_t>(x) : static_cast<uint64_t>(x);
    add(x < 0 ? 1u : 0u);
    if (magnitude > proto::kIntMax) {
      note(out_.count, "position " + std::to_string(x) + " is beyond the wire's +-2147483647");
    }
    add(magnitude > proto::kIntMax ? proto::kIntMax : static_cast<uint32_t>(magnitude));
  }
  void motor_flags(const MotorStatus& s) {
    uint32_t log2 = 0;
    while (log2 < 31 && (1u << log2) < s.microstep) ++log2;
    if (!proto::is_power_of_two(s.microstep) || log2 > kMaxLog2Microstep) {
      note(out_.count, "microstep " + std::to_string(s.microstep) + " is not a power of two up to 32768");
    }
    if (s.switches > 3) note(out_.count, "switches " + std::to_string(s.switches) + " has bits beyond end 0 and 1");
    add((s.homed ? kFlagHomed : 0u) | ((s.switches & 3u) << kFlagSwitchShift) | (s.endless ? kFlagEndless : 0u) |
        ((log2 & 0xFu) << kFlagMicrostepShift));
  }
  void later(const std::optional<uint32_t>& x) {
    if (x) add(*x);
  }

  const CommandValues& values() const { return out_; }
  const std::optional<Problem>& problem() const { return problem_; }

 private:
  void add(uint32_t v) { out_.values[out_.count++] = v; }
  void note(uint32_t field, std::string message) {
    if (!problem_) problem_ = Problem{field, 0, std::move(message)};
  }
  CommandValues out_;
  std::optional<Problem> problem_;
};

template <typename T>
T read_frame(const uint32_t* values, uint32_t count) {
  T out{};
  Reader reader(values, count);
  fields(reader, out);
  return out;
}

template <std::size_t... I>
BoardFrame make_frame(std::size_t index, const uint32_t* values, uint32_t count, std::index_sequence<I...>) {
  BoardFrame out;
  ((index == I ? (void)(out = read_frame<std::variant_alternative_t<I, BoardFrame>>(values, count)) : void()), ...);
  return out;
}

// The frame's shape for `count` values: its own, or its older form when a later field is absent.
const g::Shape& shape_of(const BoardFrame& frame, uint32_t count) {
  const g::Shape& shape = g::board_frame_shapes().shapes[frame.index()];
  return shape.older && count == shape.older->value_count ? *shape.older : shape;
}

}  // namespace

proto::BoardFrameId board_frame_id(const BoardFrame& frame) { return static_cast<proto::BoardFrameId>(frame.index()); }

const proto::BoardFrameSpec& board_frame_spec(const BoardFrame& frame) {
  return proto::board_frame_spec(board_frame_id(frame));
}

bool is_event(const BoardFrame& frame) { return proto::is_event(board_frame_spec(frame)); }

Result<BoardFrame, Diagnostic> decode_board_frame(std::string_view line, proto::ChecksumMode mode) {
  const g::ShapeTable& table = g::board_frame_shapes();
  auto frame = g::parse_frame(line, mode, table);
  if (!frame) return frame.error();
  const g::Shape& shape = *frame->shape;
  if (auto refusal = g::check_values(shape, frame->values.data(), frame->offsets.data())) {
    return std::move(*refusal);
  }
  // VER's first value says which form it must have: a board of protocol 7 reports both budgets.
  const uint32_t budgets_since = proto::feature_spec(proto::Feature::kStepBudgets).since;
  const g::Shape& version = table.shapes[static_cast<std::size_t>(proto::BoardFrameId::kVersion)];
  if (&shape == version.older && frame->values[0] >= budgets_since) {
    const uint32_t full = version.value_count;
    return g::refuse(proto::Reason::kBadLength, proto::kTokenLength, line.find('#') + 1, "length",
                     "VER of protocol " + std::to_string(frame->values[0]) + " has " + std::to_string(full + 1) +
                         " fields (both step budgets, since protocol " + std::to_string(budgets_since) +
                         ") but the length field says " + std::to_string(shape.value_count + 1),
                     full + 1, shape.value_count + 1);
  }
  return make_frame(table.index_of(shape), frame->values.data(), shape.value_count,
                    std::make_index_sequence<std::variant_size_v<BoardFrame>>{});
}

Result<CommandValues, Diagnostic> board_frame_values(const BoardFrame& frame) {
  Writer writer;
  std::visit(
      [&writer](const auto& typed) {
        auto copy = typed;  // the field lists take non-const references, for reading
        fields(writer, copy);
      },
      frame);
  const CommandValues& values = writer.values();
  const g::Shape& shape = shape_of(frame, values.count);
  const auto offsets = g::canonical_offsets(shape, values.values.data());
  if (const auto& problem = writer.problem()) {
    return g::refuse(proto::Reason::kOutOfRange, static_cast<int>(proto::kTokenFirstValue + problem->field),
                     offsets[problem->field], shape.fields[problem->field].name, problem->message, 0,
                     values.values[problem->field]);
  }
  if (auto refusal = g::check_values(shape, values.values.data(), offsets.data())) return std::move(*refusal);
  return values;
}

Result<std::string, Diagnostic> encode_board_frame(const BoardFrame& frame, proto::ChecksumMode mode) {
  auto values = board_frame_values(frame);
  if (!values) return values.error();
  return g::write_frame(shape_of(frame, values->count), values->values.data(), mode);
}

const char* motor_state_name(MotorState state) {
  switch (state) {
    case MotorState::kIdle: return "idle";
    case MotorState::kMoving: return "moving";
    case MotorState::kHoming: return "homing";
    case MotorState::kChanging: return "changing";
    case MotorState::kSelfTest: return "self_test";
  }
  return "?";
}

const char* motion_end_name(MotionEnd how) {
  switch (how) {
    case MotionEnd::kCompleted: return "completed";
    case MotionEnd::kStopped: return "stopped";
    case MotionEnd::kLimit: return "limit";
    case MotionEnd::kEmergency: return "emergency";
    case MotionEnd::kDropped: return "dropped";
    case MotionEnd::kWatchdog: return "watchdog";
  }
  return "?";
}

const char* reset_cause_name(proto::ResetCause cause) {
  const auto code = static_cast<uint32_t>(cause);
  return code < proto::kResetCauseCount ? proto::kResetCauseNames[code] : "unknown";
}

std::string reset_text(const ResetInfo& r) {
  switch (r.cause) {
    case proto::ResetCause::kPowerOn: return "power-on";
    case proto::ResetCause::kBrownOut: return "brown-out (the supply dipped)";
    case proto::ResetCause::kExternal: return "the reset pin";
    case proto::ResetCause::kWatchdog: return "the watchdog (the firmware's main loop stalled)";
    case proto::ResetCause::kSoftware: return "a software reset request";
    case proto::ResetCause::kFault: break;
    case proto::ResetCause::kUnknown: return "unknown";
  }
  auto exception_name = [](uint32_t n) -> std::string {
    if (n == 0) return "the main loop";
    if (n == 2) return "NMI";
    if (n == 3) return "HardFault";
    if (n >= 16) return "interrupt " + std::to_string(n - 16);
    return "exception " + std::to_string(n);
  };
  auto address = [](uint32_t a) {
    static constexpr char kHex[] = "0123456789ABCDEF";
    std::string out = "0x";
    for (int shift = 28; shift >= 0; shift -= 4) out += kHex[(a >> shift) & 0xF];
    return out;
  };
  // The wire drops bit 31, which only the exception-return values 0xFFFFFFFx have.
  const uint32_t lr = r.lr >= 0x7FFFFFF0u ? r.lr | 0x80000000u : r.lr;
  std::string out = "a fault (" + exception_name(r.exception) + (r.exception >= 16 ? " had no handler" : "") +
                    ") at pc " + address(r.pc) + ", lr " + address(lr);
  return out + ", in " + (r.context == 0 ? std::string("the main loop") : exception_name(r.context));
}

std::string firmware_version_text(uint32_t firmware) {
  return std::to_string(firmware / 10000) + "." + std::to_string(firmware / 100 % 100) + "." +
         std::to_string(firmware % 100);
}

namespace {

std::string at_position(int64_t position) { return "at " + position_text(position) + " (1/256 step)"; }

std::string checksum_mode_text(proto::ChecksumMode mode) {
  return mode == proto::ChecksumMode::kCrc16 ? "CRC-16" : "the seed's sum";
}

// "motors 1 and 2", "motor 3", "no motor".
std::string motors_in_mask(uint32_t mask) {
  std::string out;
  uint32_t count = 0;
  for (uint32_t motor = 1; motor <= 8; ++motor) {
    if ((mask & (1u << (motor - 1))) == 0) continue;
    out += count++ == 0 ? "" : (mask >> motor) == 0 ? " and " : ", ";
    out += std::to_string(motor);
  }
  if (count == 0) return "no motor";
  return (count == 1 ? "motor " : "motors ") + out;
}

struct Describer {
  std::string operator()(const Ack&) const { return "accepted"; }
  std::string operator()(const Nak& n) const {
    const auto code = static_cast<uint32_t>(n.reason);
    std::string out = "refused: ";
    out += code < proto::kReasonCount ? proto::reason_spec(n.reason).name : "reason " + std::to_string(code);
    if (n.token != proto::kNoToken) out += " at token " + std::to_string(n.token) + ",";
    return out + " byte " + std::to_string(n.offset);
  }
  std::string operator()(const Version& v) const {
    const uint32_t motors = v.board / 100, servos = v.board / 10 % 10, strips = v.board % 10;
    return "protocol " + std::to_string(v.protocol) + ", firmware " + firmware_version_text(v.firmware) + ", " +
           std::to_string(motors) + " motors, " + std::to_string(servos) + " servos, " + std::to_string(strips) +
           " LED strips, limit switches on " + motors_in_mask(v.switch_mask) + ", lines up to " +
           std::to_string(v.line_max) + " bytes, up to " + std::to_string(v.max_rate) + " steps/s" +
           (v.max_ramping_rate ? " (" + std::to_string(*v.max_ramping_rate) + " while a motor ramps)" : std::string()) +
           ", checksums: " +
           checksum_mode_text(v.checksum_mode) + (v.legacy ? ", legacy mode" : "");
  }
  std::string operator()(const MotorStatus& s) const {
    std::string out = "motor " + std::to_string(s.motor) + " " + motor_state_name(s.state);
    if (s.rate != 0) out += " at " + std::to_string(s.rate) + " steps/s";
    out += ", " + at_position(s.position);
    if (s.endless) {
      out += ", running until stopped";
    } else if (s.target != s.position) {
      out += ", toward " + position_text(s.target);
    }
    out += s.microstep == 1 ? ", full step" : ", 1/" + std::to_string(s.microstep) + " step";
    out += s.homed ? ", homed" : ", not homed";
    for (uint32_t end = 0; end < 2; ++end) {
      if (s.switches & (1u << end)) out += ", switch at end " + std::to_string(end) + " pressed";
    }
    return out;
  }
  std::string operator()(const BoardStatus& b) const {
    std::string out = b.emergency ? "emergency switch pressed" : "emergency switch released";
    std::string pressed;
    for (uint32_t motor = 1; motor <= proto::kMotorCount; ++motor) {
      for (uint32_t end = 0; end < 2; ++end) {
        if (!b.limit_pressed(motor, end)) continue;
        pressed += (pressed.empty() ? "" : ", ") + std::string("motor ") + std::to_string(motor) + " end " +
                   std::to_string(end);
      }
    }
    out += "; limit switches pressed: " + (pressed.empty() ? std::string("none") : pressed);
    auto servo = [](uint32_t n, uint32_t us) {
      return "servo " + std::to_string(n) + (us == 0 ? std::string(" released") : " at " + std::to_string(us) + " us");
    };
    return out + "; " + servo(1, b.servo1_us) + ", " + servo(2, b.servo2_us);
  }
  std::string operator()(const StripStatus& s) const {
    return "LED strip " + std::to_string(s.strip) + " is R" + std::to_string(s.r) + " G" + std::to_string(s.g) +
           " B" + std::to_string(s.b) + " W" + std::to_string(s.w);
  }
  std::string operator()(const SettingValue& s) const {
    if (s.setting < 1 || s.setting > proto::kSettingCount) {
      return "stepper " + std::to_string(s.motor) + ": setting " + std::to_string(s.setting) + " is " +
             std::to_string(s.value);
    }
    const proto::SettingSpec& spec = proto::kSettings[s.setting - 1];
    return "stepper " + std::to_string(s.motor) + ": " + spec.name + " (" + spec.meaning + ") is " +
           std::to_string(s.value);
  }
  std::string operator()(const Booted& b) const {
    return "the board booted: protocol " + std::to_string(b.protocol) + ", firmware " +
           firmware_version_text(b.firmware) + "; checksums: the seed's sum";
  }
  std::string operator()(const ResetStatus& r) const { return "last reset: " + reset_text(r); }
  std::string operator()(const ResetEvent& r) const { return "the board reset by " + reset_text(r); }
  std::string operator()(const MotionEnded& e) const {
    const std::string who = "motor " + std::to_string(e.motor);
    switch (e.how) {
      case MotionEnd::kCompleted: return who + " completed its move " + at_position(e.position);
      case MotionEnd::kStopped: return who + " stopped " + at_position(e.position);
      case MotionEnd::kLimit: return who + " halted by a limit switch " + at_position(e.position);
      case MotionEnd::kEmergency: return who + " halted by the emergency switch " + at_position(e.position);
      case MotionEnd::kDropped: return who + ": a waiting move was dropped, " + at_position(e.position);
      case MotionEnd::kWatchdog:
        return who + " braked by the link watchdog (no line from the host) " + at_position(e.position);
    }
    return who;
  }
  std::string operator()(const HomingEnded& h) const {
    const std::string who = "motor " + std::to_string(h.motor);
    return h.homed ? who + " homed " + at_position(h.position)
                   : who + " did not find its switch while homing; " + at_position(h.position);
  }
  std::string operator()(const LimitChanged& l) const {
    return "motor " + std::to_string(l.motor) + " limit switch at end " + std::to_string(l.end) +
           (l.pressed ? " pressed" : " released");
  }
  std::string operator()(const EmergencyChanged& e) const {
    return e.pressed ? "emergency switch pressed" : "emergency switch released";
  }
  std::string operator()(const DriverFault& f) const {
    static constexpr const char* kBits[] = {"OTS", "AOCP", "BOCP", "APDF", "BPDF", "UVLO", "STD", "STDLAT"};
    std::string bits;
    for (uint32_t bit = 0; bit < 8; ++bit) {
      if (f.status & (1u << bit)) bits += (bits.empty() ? "" : ", ") + std::string(kBits[bit]);
    }
    static constexpr char kHex[] = "0123456789ABCDEF";
    const std::string hex = {'0', 'x', kHex[(f.status >> 4) & 0xF], kHex[f.status & 0xF]};
    return "motor " + std::to_string(f.motor) + " driver fault: " + (bits.empty() ? std::string("none") : bits) +
           " (STATUS " + hex + ")";
  }
  std::string operator()(const WatchdogStatus& w) const {
    std::string out = w.timeout_ms == 0 ? "link watchdog off"
                                        : "link watchdog armed: " + std::to_string(w.timeout_ms) + " ms";
    return out + (w.fired ? "; it fired: the board braked every motor when the host went silent" : "");
  }
};

}  // namespace

std::string describe(const BoardFrame& frame) { return std::visit(Describer{}, frame); }

}  // namespace hmc
