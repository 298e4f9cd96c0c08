// FrameParser: cuts the serial stream into lines and judges each one as docs/protocol.md
// defines, applying "The order of checks" step by step so that the first failing check is the
// one reported, exactly as any other parser of that page reports it.
#include "frame_parser.h"

namespace hmc::fw {
namespace {

using proto::CommandSpec;
using proto::FieldSpec;
using proto::Reason;

// The tokens the length field does not count: STX, the length itself, the checksum and ETX.
constexpr uint32_t kUncountedTokens = 4;
// Stands for "this command has no action"; no field can hold it, as values stop at kIntMax.
constexpr uint32_t kNoAction = ~uint32_t{0};

// True when every field whose check depends on the action comes after the action field, so the
// range checks, run left to right, have already accepted the action when they need it.
constexpr bool action_precedes_its_dependents(const CommandSpec& command) {
  for (uint32_t i = 0; i < command.value_count; ++i) {
    const bool depends =
        (command.fields[i].flags & (proto::kUncheckedOnStop | proto::kZeroAllowedOnHome)) != 0;
    if (depends && (command.action_field < 0 || i <= static_cast<uint32_t>(command.action_field))) {
      return false;
    }
  }
  return true;
}

// A setting's value follows the field that names the setting, whose range indexes kSettings.
constexpr bool setting_values_follow_their_setting(const CommandSpec& command) {
  for (uint32_t i = 0; i < command.value_count; ++i) {
    if ((command.fields[i].flags & proto::kSettingValue) == 0) continue;
    if (i == 0 || command.fields[i - 1].min < 1 || command.fields[i - 1].max > proto::kSettingCount) {
      return false;
    }
  }
  return true;
}

// Checks the command table against what this parser relies on.
constexpr bool command_table_fits() {
  for (const CommandSpec& command : proto::kCommands) {
    if (command.value_count > proto::kMaxCommandValues || !action_precedes_its_dependents(command) ||
        !setting_values_follow_their_setting(command)) {
      return false;
    }
  }
  return true;
}
static_assert(command_table_fits(), "commands fit kMaxCommandValues and name their action first");
static_assert(proto::kLineMax + 1 < proto::kNoToken, "token indices and offsets fit a byte");

// A token's place in the line: bytes [begin, end).
struct Span {
  uint32_t begin;
  uint32_t end;
};

// Where each '#'-separated token of a frame starts. A frame of kLineMax '#' has kLineMax + 1
// tokens; one extra entry marks where a token after the last would start, so that every token
// ends one byte (its '#') before the next one starts.
struct Tokens {
  uint8_t start[proto::kLineMax + 2];
  uint32_t count;

  // The bytes of token `index`, which must be below `count`.
  Span at(uint32_t index) const {
    return {start[index], static_cast<uint32_t>(start[index + 1]) - 1u};
  }
};

// Spaces and tabs around a frame are ignored.
bool is_blank(uint8_t byte) { return byte == ' ' || byte == '\t'; }

// Only printable ASCII other than space may appear inside a frame.
bool is_frame_byte(uint8_t byte) { return byte >= '!' && byte <= '~'; }

// Whether a token holds exactly `text` (case-sensitive).
bool token_is(const uint8_t* line, const Span& token, const char* text) {
  uint32_t i = token.begin;
  for (; *text != '\0'; ++text, ++i) {
    if (i == token.end || line[i] != static_cast<uint8_t>(*text)) return false;
  }
  return i == token.end;
}

// Reads a token as a protocol number: 1 to kMaxDigits decimal digits, at most kIntMax.
bool read_number(const uint8_t* line, const Span& token, uint32_t& value) {
  const uint32_t digits = token.end - token.begin;
  if (digits == 0 || digits > proto::kMaxDigits) return false;
  uint32_t number = 0;
  for (uint32_t i = token.begin; i < token.end; ++i) {
    if (line[i] < '0' || line[i] > '9') return false;
    // Checked before multiplying: beyond kIntMax / 10 any further digit leaves the range, and
    // stopping there keeps ten digits from overflowing 32 bits.
    if (number > proto::kIntMax / 10) return false;
    number = number * 10 + static_cast<uint32_t>(line[i] - '0');
    if (number > proto::kIntMax) return false;
  }
  value = number;
  return true;
}

// The command table entry a name token names, or null.
const CommandSpec* find_command(const uint8_t* line, const Span& name) {
  for (const CommandSpec& command : proto::kCommands) {
    if (token_is(line, name, command.name)) return &command;
  }
  return nullptr;
}

// Whether a value suits its field, given the command's action (kNoAction when it has none) and
// the value before it (a setting id, for a setting's value).
bool in_range(const FieldSpec& field, uint32_t value, uint32_t action, uint32_t previous) {
  if ((field.flags & proto::kSettingValue) != 0) {
    const proto::SettingSpec& setting = proto::kSettings[previous - 1];
    return value >= setting.min && value <= setting.max;
  }
  if ((field.flags & proto::kUncheckedOnStop) != 0 && action == proto::kActionStop) return true;
  if ((field.flags & proto::kZeroAllowedOnHome) != 0 && action == proto::kActionHome &&
      value == 0) {
    return true;
  }
  if (value < field.min || value > field.max) return false;
  return (field.flags & proto::kPowerOfTwo) == 0 || proto::is_power_of_two(value);
}

// Stores an accepted command; values come in the order of the command's field table and have
// passed their range checks, so every narrowing below is lossless.
void fill_command(proto::CommandId id, const uint32_t* values, Command& command) {
  command.id = id;
  switch (id) {
    case proto::CommandId::kStepper:
      command.stepper = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1]),
                         values[2], values[3], values[4]};
      break;
    case proto::CommandId::kServo:
      command.servo = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1])};
      break;
    case proto::CommandId::kLed:
      command.led = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1]),
                     static_cast<uint8_t>(values[2]), static_cast<uint8_t>(values[3]),
                     static_cast<uint8_t>(values[4])};
      break;
    case proto::CommandId::kVersion:
      break;
    case proto::CommandId::kStatus:
      command.status = {static_cast<uint8_t>(values[0])};
      break;
    case proto::CommandId::kSet:
    case proto::CommandId::kGet:
      command.setting = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1]),
                         id == proto::CommandId::kSet ? values[2] : 0};
      break;
    case proto::CommandId::kLimits:
      command.limits = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1]), values[2],
                        static_cast<uint8_t>(values[3]), values[4]};
      break;
    case proto::CommandId::kChecksumMode:
      command.checksum_mode = {static_cast<uint8_t>(values[0])};
      break;
    case proto::CommandId::kWatchdog:
      command.watchdog = {values[0]};
      break;
    case proto::CommandId::kSetPosition:
      command.position = {static_cast<uint8_t>(values[0]), static_cast<uint8_t>(values[1]), values[2]};
      break;
  }
}

// Writes a whole verdict, with 0 in every field it does not name (a refusal's command too);
// returns true, as the line got a verdict. Field by field, so no library routine is needed.
bool give_verdict(Verdict& out, Reason reason, uint32_t token = 0, uint32_t offset = 0,
                  uint32_t expected = 0, uint32_t found = 0) {
  out.reason = reason;
  out.token = static_cast<uint8_t>(token);
  out.offset = static_cast<uint8_t>(offset);
  out.expected = expected;
  out.found = found;
  out.command.id = proto::CommandId::kStepper;
  out.command.stepper.motor = 0;
  out.command.stepper.dir = 0;
  out.command.stepper.microstep = 0;
  out.command.stepper.steps = 0;
  out.command.stepper.delay_us = 0;
  return true;
}

// Steps 12 to 16 and acceptance: the values, checksum, ranges and switch of a frame whose
// structure, length and name are right, so it has exactly value_count + 5 tokens.
bool judge_values(const uint8_t* line, const Tokens& tokens, const CommandSpec& command,
                  proto::ChecksumMode mode, Verdict& out) {
  const uint32_t count = command.value_count;

  // 12. Value numbers, summed mod 256 on the way.
  uint32_t values[proto::kMaxValues];
  uint32_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const Span value = tokens.at(proto::kTokenFirstValue + i);
    if (!read_number(line, value, values[i])) {
      return give_verdict(out, Reason::kBadNumber, proto::kTokenFirstValue + i, value.begin);
    }
    sum = (sum + values[i]) & 0xFFu;
  }

  // 13. Checksum number; in CRC-16 mode exactly kCrcDigits digits, so no digit can move across
  // the '#' into the field the CRC does not cover.
  const uint32_t checksum_token = proto::kTokenFirstValue + count;
  const Span checksum_span = tokens.at(checksum_token);
  const bool crc = mode == proto::ChecksumMode::kCrc16;
  uint32_t checksum = 0;
  if (!read_number(line, checksum_span, checksum) ||
      (crc && checksum_span.end - checksum_span.begin != proto::kCrcDigits)) {
    return give_verdict(out, Reason::kBadNumber, checksum_token, checksum_span.begin);
  }
  if (checksum > (crc ? proto::kCrcMax : proto::kChecksumMax)) {
    return give_verdict(out, Reason::kOutOfRange, checksum_token, checksum_span.begin, 0, checksum);
  }

  // 14. Checksum: the sum, or the CRC of the frame's bytes before the checksum field.
  const Span start = tokens.at(proto::kTokenStart);
  const uint32_t want =
      crc ? proto::crc16(line + start.begin, checksum_span.begin - start.begin) : sum;
  if (checksum != want) {
    return give_verdict(out, Reason::kChecksumMismatch, checksum_token, checksum_span.begin, want,
                        checksum);
  }

  // 15. Ranges, left to right.
  const uint32_t action =
      command.action_field < 0 ? kNoAction : values[static_cast<uint32_t>(command.action_field)];
  for (uint32_t i = 0; i < count; ++i) {
    if (!in_range(command.fields[i], values[i], action, i > 0 ? values[i - 1] : 0)) {
      return give_verdict(out, Reason::kOutOfRange, proto::kTokenFirstValue + i,
                          tokens.at(proto::kTokenFirstValue + i).begin, 0, values[i]);
    }
  }

  // 16. Switch: what an action moves (the motor) is the first value.
  if (action == proto::kActionHome && !proto::motor_has_switches(values[0])) {
    return give_verdict(out, Reason::kNoSwitch, proto::kTokenFirstValue,
                        tokens.at(proto::kTokenFirstValue).begin);
  }

  give_verdict(out, Reason::kOk);
  fill_command(command.id, values, out.command);
  return true;
}

}  // namespace

uint32_t command_values(const Command& command, uint32_t (&values)[proto::kMaxValues]) {
  switch (command.id) {
    case proto::CommandId::kStepper: {
      const StepperCommand& c = command.stepper;
      values[0] = c.motor, values[1] = c.dir, values[2] = c.microstep, values[3] = c.steps, values[4] = c.delay_us;
      break;
    }
    case proto::CommandId::kServo:
      values[0] = command.servo.servo, values[1] = command.servo.angle;
      break;
    case proto::CommandId::kLed: {
      const LedCommand& c = command.led;
      values[0] = c.strip, values[1] = c.r, values[2] = c.g, values[3] = c.b, values[4] = c.w;
      break;
    }
    case proto::CommandId::kVersion:
      break;
    case proto::CommandId::kStatus:
      values[0] = command.status.unit;
      break;
    case proto::CommandId::kSet:
    case proto::CommandId::kGet: {
      const SettingCommand& c = command.setting;
      values[0] = c.motor, values[1] = c.setting, values[2] = c.value;
      break;
    }
    case proto::CommandId::kLimits: {
      const LimitsCommand& c = command.limits;
      values[0] = c.motor, values[1] = c.low_sign, values[2] = c.low, values[3] = c.high_sign, values[4] = c.high;
      break;
    }
    case proto::CommandId::kChecksumMode:
      values[0] = command.checksum_mode.mode;
      break;
    case proto::CommandId::kWatchdog:
      values[0] = command.watchdog.timeout_ms;
      break;
    case proto::CommandId::kSetPosition:
      values[0] = command.position.motor, values[1] = command.position.sign, values[2] = command.position.position;
      break;
  }
  return proto::command_spec(command.id).value_count;
}

// Starts with an empty line and an all-zero verdict; line_ needs no clearing, as only its first
// length_ bytes are ever read.
FrameParser::FrameParser() : length_(0), last_length_(0), mode_(proto::ChecksumMode::kSum) { give_verdict(verdict_, Reason::kOk); }

// Stores the byte, or judges the line when the byte ends it.
bool FrameParser::feed(uint8_t byte) {
  if (byte == '\r' || byte == '\n') {
    const bool judged = parse_line(line_, length_, verdict_, mode_);
    last_length_ = length_ < proto::kLineMax ? length_ : proto::kLineMax;
    length_ = 0;
    return judged;
  }
  if (length_ < proto::kLineMax) line_[length_] = byte;
  // Counting stops one past the limit: that already means line_too_long, and a count that never
  // grows cannot wrap around on an endless line.
  if (length_ <= proto::kLineMax) ++length_;
  return false;
}

uint8_t FrameParser::token_offset(uint8_t token) const {
  uint32_t i = 0;
  while (i < last_length_ && is_blank(line_[i])) ++i;
  for (uint8_t seen = 0; seen < token && i < last_length_; ++i) {
    if (line_[i] == '#') ++seen;
  }
  return static_cast<uint8_t>(i);
}

// Steps 1 to 11 of the order of checks; judge_values() does the rest.
bool FrameParser::parse_line(const uint8_t* line, uint32_t length, Verdict& out,
                             proto::ChecksumMode mode) {
  // 1. Length; nothing past the limit is read.
  if (length > proto::kLineMax) {
    return give_verdict(out, Reason::kLineTooLong, proto::kNoToken, proto::kLineMax);
  }

  // 2. Blank.
  uint32_t begin = 0;
  uint32_t end = length;
  while (begin < end && is_blank(line[begin])) ++begin;
  while (end > begin && is_blank(line[end - 1])) --end;
  if (begin == end) return false;

  // 3. Bytes, and 4. split at every '#' in the same pass; a bad byte's token is the number of
  // '#' before it.
  Tokens tokens;
  tokens.count = 1;
  tokens.start[0] = static_cast<uint8_t>(begin);
  for (uint32_t i = begin; i < end; ++i) {
    if (!is_frame_byte(line[i])) return give_verdict(out, Reason::kBadByte, tokens.count - 1, i);
    if (line[i] == '#') tokens.start[tokens.count++] = static_cast<uint8_t>(i + 1);
  }
  tokens.start[tokens.count] = static_cast<uint8_t>(end + 1);
  const uint32_t k = tokens.count;

  // 5. Start.
  const Span start = tokens.at(proto::kTokenStart);
  if (!token_is(line, start, "STX")) {
    return give_verdict(out, Reason::kBadStart, proto::kTokenStart, start.begin);
  }

  // 6. End. A single token needs no test of its own: it has just proved to be STX, not ETX.
  const Span last = tokens.at(k - 1);
  if (!token_is(line, last, "ETX")) {
    return give_verdict(out, Reason::kBadEnd, k - 1, last.begin);
  }

  // 7. Room: the length counts at least the name. Here k - 4 is never positive, so found is 0.
  const Span length_span = tokens.at(proto::kTokenLength);
  if (k < kUncountedTokens + 1) {
    return give_verdict(out, Reason::kBadLength, proto::kTokenLength, length_span.begin);
  }

  // 8. Length number.
  uint32_t declared = 0;
  if (!read_number(line, length_span, declared)) {
    return give_verdict(out, Reason::kBadNumber, proto::kTokenLength, length_span.begin);
  }

  // 9. Length agrees with the frame.
  if (declared != k - kUncountedTokens) {
    return give_verdict(out, Reason::kBadLength, proto::kTokenLength, length_span.begin, declared,
                        k - kUncountedTokens);
  }

  // 10. Name.
  const Span name = tokens.at(proto::kTokenName);
  const CommandSpec* command = find_command(line, name);
  if (command == nullptr) {
    return give_verdict(out, Reason::kUnknownCommand, proto::kTokenName, name.begin);
  }

  // 11. Length agrees with the command.
  const uint32_t command_length = command->value_count + 1u;
  if (declared != command_length) {
    return give_verdict(out, Reason::kBadLength, proto::kTokenLength, length_span.begin,
                        command_length, declared);
  }

  return judge_values(line, tokens, *command, mode, out);
}

}  // namespace hmc::fw
