// The host codec: decode with diagnostics, validate, lint, encode, and typed-input parsing.
//
// decode() follows docs/protocol.md's order of checks step by step. It works on string views
// over the caller's line and allocates only to explain a refusal or a warning.
#include "hmc/codec.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <optional>

namespace hmc {
namespace {

using proto::Reason;

constexpr std::string_view kStart = "STX";
constexpr std::string_view kEnd = "ETX";
// Enough tokens for a line of kLineMax '#' bytes.
constexpr std::size_t kMaxTokens = proto::kLineMax + 1;

struct Token {
  std::string_view text;
  std::size_t offset = 0;  // in the line
};

bool is_blank_byte(char c) { return c == ' ' || c == '\t'; }
bool is_frame_byte(char c) { return c >= '!' && c <= '~'; }

std::string_view strip_blanks(std::string_view s, std::size_t& lead) {
  lead = 0;
  while (lead < s.size() && is_blank_byte(s[lead])) ++lead;
  std::size_t end = s.size();
  while (end > lead && is_blank_byte(s[end - 1])) --end;
  return s.substr(lead, end - lead);
}

// 1-10 decimal digits up to INT_MAX; anything else is not a number.
std::optional<uint32_t> parse_number(std::string_view text) {
  if (text.empty() || text.size() > proto::kMaxDigits) return std::nullopt;
  uint64_t value = 0;
  const char* end = text.data() + text.size();
  auto [stop, err] = std::from_chars(text.data(), end, value, 10);
  if (err != std::errc() || stop != end || value > proto::kIntMax) return std::nullopt;
  return static_cast<uint32_t>(value);
}

bool has_leading_zero(std::string_view number) { return number.size() > 1 && number[0] == '0'; }

std::string quote(std::string_view s) {
  std::string out = "'";
  for (char byte : s) {
    const auto c = static_cast<unsigned char>(byte);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
    } else {
      static constexpr char kHex[] = "0123456789ABCDEF";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
    }
  }
  return out + "'";
}

std::string range_text(const proto::FieldSpec& f) {
  std::string out = std::to_string(f.min) + "-" + std::to_string(f.max);
  if (f.flags & proto::kPowerOfTwo) out = "a power of two " + out;
  return out;
}

// Names token `token` of a frame of `k` tokens whose command is `spec` (or unknown).
std::string token_name(const proto::CommandSpec* spec, std::size_t k, int token) {
  if (token == kNoToken) return "";
  const auto t = static_cast<std::size_t>(token);
  if (t == proto::kTokenStart) return "start";
  if (t == proto::kTokenLength) return "length";
  if (t == proto::kTokenName) return "name";
  if (k >= 2 && t == k - 1) return "end";
  if (k >= 5 && t == k - 2) return "checksum";
  const std::size_t value = t - proto::kTokenFirstValue;
  if (spec && value < spec->value_count) return spec->fields[value].name;
  return "value " + std::to_string(value + 1);
}

Diagnostic refuse(Reason reason, int token, std::size_t offset, std::string field, std::string message,
                  uint32_t expected = 0, uint32_t found = 0) {
  Diagnostic d;
  d.reason = reason;
  d.token = token;
  d.offset = offset;
  d.expected = expected;
  d.found = found;
  d.field = std::move(field);
  d.message = std::move(message);
  return d;
}

using Tokens = std::array<Token, kMaxTokens>;

// Splits `text` (at most kLineMax bytes) at every '#'; offsets start at `base`. Returns the count.
std::size_t split(std::string_view text, std::size_t base, Tokens& tokens) {
  std::size_t k = 0;
  for (std::size_t begin = 0;;) {
    const std::size_t hash = text.find('#', begin);
    const std::size_t end = hash == std::string_view::npos ? text.size() : hash;
    tokens[k++] = Token{text.substr(begin, end - begin), base + begin};
    if (hash == std::string_view::npos) return k;
    begin = hash + 1;
  }
}

Diagnostic value_not_a_number(const proto::CommandSpec& spec, uint32_t i, std::string_view text, std::size_t offset) {
  return refuse(Reason::kBadNumber, static_cast<int>(proto::kTokenFirstValue + i), offset, spec.fields[i].name,
                std::string(spec.fields[i].name) + " is " + quote(text) +
                    ": expected an unsigned decimal number of 1-10 digits, at most 2147483647");
}

Diagnostic unknown_command(std::string_view name, std::size_t offset) {
  return refuse(Reason::kUnknownCommand, proto::kTokenName, offset, "name",
                "unknown command " + quote(name) + "; known commands are STM, SVM and LED (case-sensitive)");
}

// The value of the command's action field (STM's dir), if it has one.
std::optional<uint32_t> action_of(const proto::CommandSpec& spec, const uint32_t* values) {
  if (spec.action_field < 0) return std::nullopt;
  return values[static_cast<std::size_t>(spec.action_field)];
}

// Steps 15-16: ranges left to right under the action's exemptions, then the switch rule.
// `offsets[i]` is where value i starts in the text the diagnostic refers to.
std::optional<Diagnostic> check_values(const proto::CommandSpec& spec, const uint32_t* values,
                                       const std::size_t* offsets) {
  // The action field precedes every field whose check depends on it, so it is checked first.
  const std::optional<uint32_t> action = action_of(spec, values);
  const bool stopping = action == proto::kActionStop;
  const bool homing = action == proto::kActionHome;
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    const proto::FieldSpec& f = spec.fields[i];
    const uint32_t v = values[i];
    if ((f.flags & proto::kUncheckedOnStop) && stopping) continue;
    if (v == 0 && (f.flags & proto::kZeroAllowedOnHome) && homing) continue;
    const bool in_range = v >= f.min && v <= f.max && (!(f.flags & proto::kPowerOfTwo) || proto::is_power_of_two(v));
    if (in_range) continue;
    std::string message = std::string(f.name) + " is " + std::to_string(v) + ": expected " + range_text(f);
    if (f.flags & proto::kZeroAllowedOnHome) message += " (0 only when homing)";
    return refuse(Reason::kOutOfRange, static_cast<int>(proto::kTokenFirstValue + i), offsets[i], f.name,
                  std::move(message), 0, v);
  }
  if (homing && !proto::motor_has_switches(values[0])) {
    return refuse(Reason::kNoSwitch, proto::kTokenFirstValue, offsets[0], spec.fields[0].name,
                  "motor " + std::to_string(values[0]) +
                      " has no limit switch to home against; only motors with switches (1 and 2) can home");
  }
  return std::nullopt;
}

std::string checksum_explanation(const uint32_t* values, uint32_t count) {
  std::string sum_text;
  uint64_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) {
    if (i) sum_text += "+";
    sum_text += std::to_string(values[i]);
    sum += values[i];
  }
  return sum_text + " = " + std::to_string(sum) + ", mod 256 = " + std::to_string(sum % 256);
}

uint32_t checksum_of(const uint32_t* values, uint32_t count) {
  uint32_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) sum = (sum + (values[i] & 0xFFu)) & 0xFFu;
  return sum;
}

}  // namespace

bool is_blank(std::string_view line) {
  return std::all_of(line.begin(), line.end(), is_blank_byte);
}

uint32_t checksum(const Command& command) {
  const CommandValues v = command_values(command);
  return checksum_of(v.values.data(), v.count);
}

Result<Decoded, Diagnostic> decode(std::string_view line) {
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);

  // 1. Length.
  if (line.size() > proto::kLineMax) {
    return refuse(Reason::kLineTooLong, kNoToken, proto::kLineMax, "",
                  "line is " + std::to_string(line.size()) + " bytes long; at most " +
                      std::to_string(proto::kLineMax) + " fit before the line end");
  }
  // 2. Blank.
  std::size_t lead = 0;
  const std::string_view frame = strip_blanks(line, lead);
  if (frame.empty()) {
    return refuse(Reason::kBadStart, proto::kTokenStart, 0, "start", "no frame on the line: expected 'STX#...#ETX'");
  }
  // 4. Split (before the byte check, so a bad byte can be named by its field).
  Tokens tokens;
  const std::size_t k = split(frame, lead, tokens);
  const std::string_view name_text = k > proto::kTokenName ? tokens[proto::kTokenName].text : std::string_view{};
  const proto::CommandSpec* named = find_command(name_text);
  auto name_of = [&](int token) { return token_name(named, k, token); };

  // 3. Bytes.
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (is_frame_byte(frame[i])) continue;
    const auto token = static_cast<int>(std::count(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(i), '#'));
    std::string what = is_blank_byte(frame[i]) ? "a blank" : "byte " + quote(frame.substr(i, 1));
    return refuse(Reason::kBadByte, token, lead + i, name_of(token),
                  what + " at offset " + std::to_string(lead + i) + " in field '" + name_of(token) +
                      "': inside a frame only '!'..'~' may appear (blanks only around it)");
  }
  // 5. Start.
  if (tokens[0].text != kStart) {
    std::string message = "frame must start with 'STX', found " + quote(tokens[0].text);
    if (frame.rfind("[#", 0) == 0) {
      message += " (this is command-set notation, not a wire frame; `hmc frame encode` frames it)";
    } else if (frame.rfind("[STX#", 0) == 0) {
      message += " (the spec prints frames in brackets; the brackets are not part of the frame)";
    }
    return refuse(Reason::kBadStart, proto::kTokenStart, tokens[0].offset, "start", std::move(message));
  }
  // 6. End.
  if (k < 2 || tokens[k - 1].text != kEnd) {
    const auto last = static_cast<int>(k - 1);
    return refuse(Reason::kBadEnd, last, tokens[k - 1].offset, name_of(last),
                  "frame must end with '#ETX', found " + quote(tokens[k - 1].text) + " as its last field");
  }
  // 7. Room.
  const Token& len_token = tokens[proto::kTokenLength];
  const auto fields_present = static_cast<uint32_t>(k >= 4 ? k - 4 : 0);
  if (k < 5) {
    return refuse(Reason::kBadLength, proto::kTokenLength, len_token.offset, "length",
                  "frame has " + std::to_string(k) +
                      " fields; it needs at least STX, length, name, checksum and ETX",
                  0, fields_present);
  }
  // 8. Length number.
  const std::optional<uint32_t> len = parse_number(len_token.text);
  if (!len) {
    return refuse(Reason::kBadNumber, proto::kTokenLength, len_token.offset, "length",
                  "length field is " + quote(len_token.text) + ": expected an unsigned decimal number");
  }
  // 9. Length agrees with the frame.
  if (*len != fields_present) {
    return refuse(Reason::kBadLength, proto::kTokenLength, len_token.offset, "length",
                  "length field says " + std::to_string(*len) + " fields but the frame has " +
                      std::to_string(fields_present) + " between length and checksum",
                  *len, fields_present);
  }
  // 10. Name.
  if (!named) {
    return unknown_command(name_text, tokens[proto::kTokenName].offset);
  }
  const proto::CommandSpec& spec = *named;
  // 11. Length agrees with the command.
  if (*len != spec.value_count + 1u) {
    return refuse(Reason::kBadLength, proto::kTokenLength, len_token.offset, "length",
                  std::string(spec.name) + " has " + std::to_string(spec.value_count + 1) +
                      " fields (its name and " + std::to_string(spec.value_count) +
                      " values) but the length field says " + std::to_string(*len),
                  spec.value_count + 1u, *len);
  }
  // 12. Value numbers.
  std::array<uint32_t, proto::kMaxValues> values{};
  std::array<std::size_t, proto::kMaxValues> offsets{};
  bool canonical = lead == 0 && frame.size() == line.size() && !has_leading_zero(len_token.text);
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    const Token& t = tokens[proto::kTokenFirstValue + i];
    const std::optional<uint32_t> v = parse_number(t.text);
    if (!v) {
      return value_not_a_number(spec, i, t.text, t.offset);
    }
    values[i] = *v;
    offsets[i] = t.offset;
    canonical = canonical && !has_leading_zero(t.text);
  }
  // 13. Checksum number.
  const int checksum_token = static_cast<int>(k - 2);
  const Token& cs_token = tokens[k - 2];
  const std::optional<uint32_t> given = parse_number(cs_token.text);
  if (!given) {
    return refuse(Reason::kBadNumber, checksum_token, cs_token.offset, "checksum",
                  "checksum is " + quote(cs_token.text) + ": expected a decimal number 0-255");
  }
  if (*given > proto::kChecksumMax) {
    return refuse(Reason::kOutOfRange, checksum_token, cs_token.offset, "checksum",
                  "checksum is " + std::to_string(*given) + ": a checksum is 0-255", 0, *given);
  }
  // 14. Checksum.
  const uint32_t want = checksum_of(values.data(), spec.value_count);
  if (*given != want) {
    return refuse(Reason::kChecksumMismatch, checksum_token, cs_token.offset, "checksum",
                  "checksum is " + std::to_string(*given) + " where " + std::to_string(want) + " was expected (" +
                      checksum_explanation(values.data(), spec.value_count) + ")",
                  want, *given);
  }
  canonical = canonical && !has_leading_zero(cs_token.text);
  // 15-16. Ranges and rules.
  if (auto refusal = check_values(spec, values.data(), offsets.data())) return std::move(*refusal);

  Decoded out{make_command(spec.id, values.data()), canonical, {}};
  out.warnings = lint(out.command);
  return out;
}

Result<Command, Diagnostic> validate(const Command& command) {
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  // Offsets in the canonical frame: "STX#<len>#<NAME>#v1#v2...".
  std::array<std::size_t, proto::kMaxValues> offsets{};
  std::size_t at = kStart.size() + 1 + std::to_string(spec.value_count + 1).size() + 1 +
                   std::string_view(spec.name).size() + 1;
  for (uint32_t i = 0; i < v.count; ++i) {
    offsets[i] = at;
    at += std::to_string(v.values[i]).size() + 1;
  }
  if (auto refusal = check_values(spec, v.values.data(), offsets.data())) return std::move(*refusal);
  return command;
}

std::vector<Warning> lint(const Command& command) {
  std::vector<Warning> out;
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  const std::optional<uint32_t> action = action_of(spec, v.values.data());
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    const proto::FieldSpec& f = spec.fields[i];
    if (f.advised_min == 0 && f.advised_max == 0) continue;
    if (action == proto::kActionStop && (f.flags & proto::kUncheckedOnStop)) continue;
    if (v.values[i] == 0 && (f.flags & proto::kZeroAllowedOnHome) && action == proto::kActionHome) continue;
    if (v.values[i] >= f.advised_min && v.values[i] <= f.advised_max) continue;
    out.push_back({f.name, std::string(f.name) + " " + std::to_string(v.values[i]) + " is outside the spec's advised " +
                               std::to_string(f.advised_min) + "-" + std::to_string(f.advised_max) +
                               (v.values[i] < f.advised_min ? " (the motor may stall or skip steps)"
                                                            : " (very slow)")});
  }
  return out;
}

Result<std::string, Diagnostic> encode(const Command& command) {
  auto valid = validate(command);
  if (!valid) return valid.error();
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  std::string out;
  out.reserve(64);
  out += kStart;
  out += '#';
  out += std::to_string(spec.value_count + 1);
  out += '#';
  out += spec.name;
  for (uint32_t i = 0; i < v.count; ++i) {
    out += '#';
    out += std::to_string(v.values[i]);
  }
  out += '#';
  out += std::to_string(checksum_of(v.values.data(), v.count));
  out += '#';
  out += kEnd;
  return out;
}

Result<Command, Diagnostic> parse_input(std::string_view text) {
  std::size_t lead = 0;
  const std::string_view body = strip_blanks(text, lead);
  if (body.empty() || body.front() != '[') {
    auto decoded = decode(text);
    if (!decoded) return decoded.error();
    return decoded->command;
  }
  // Command-set notation: [#NAME#v1#...#vn], held to the frame's length limit.
  if (body.size() > proto::kLineMax) {
    return refuse(Reason::kLineTooLong, kNoToken, lead + proto::kLineMax, "",
                  "command-set notation is " + std::to_string(body.size()) + " bytes long; at most " +
                      std::to_string(proto::kLineMax) + " fit on a line");
  }
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (!is_frame_byte(body[i])) {
      return refuse(Reason::kBadByte, kNoToken, lead + i, "",
                    "byte " + quote(body.substr(i, 1)) + " at offset " + std::to_string(lead + i) +
                        " cannot appear in command-set notation");
    }
  }
  if (body.back() != ']') {
    return refuse(Reason::kBadEnd, kNoToken, lead + body.size() - 1, "end",
                  "command-set notation must end with ']'");
  }
  if (body.size() < 2 || body[1] != '#') {
    return refuse(Reason::kBadStart, kNoToken, lead, "start", "command-set notation must start with '[#', as in [#SVM#1#135]");
  }
  const std::string_view inner = body.substr(2, body.size() - 3);
  Tokens tokens;
  const std::size_t k = split(inner, lead + 2, tokens);
  const proto::CommandSpec* spec = find_command(tokens[0].text);
  if (!spec) {
    return unknown_command(tokens[0].text, tokens[0].offset);
  }
  if (k - 1 != spec->value_count) {
    return refuse(Reason::kBadLength, proto::kTokenLength, tokens[0].offset, "length",
                  std::string(spec->name) + " takes " + std::to_string(spec->value_count) + " values, got " +
                      std::to_string(k - 1),
                  spec->value_count, static_cast<uint32_t>(k - 1));
  }
  std::array<uint32_t, proto::kMaxValues> values{};
  std::array<std::size_t, proto::kMaxValues> offsets{};
  for (uint32_t i = 0; i < spec->value_count; ++i) {
    const Token& t = tokens[1 + i];
    const std::optional<uint32_t> v = parse_number(t.text);
    if (!v) {
      return value_not_a_number(*spec, i, t.text, t.offset);
    }
    values[i] = *v;
    offsets[i] = t.offset;
  }
  if (auto refusal = check_values(*spec, values.data(), offsets.data())) return std::move(*refusal);
  return make_command(spec->id, values.data());
}

Result<Command, Diagnostic> command_from_words(const std::vector<std::string>& words) {
  if (words.empty()) {
    return refuse(Reason::kUnknownCommand, proto::kTokenName, 0, "name", "no command given: expected STM, SVM or LED");
  }
  std::string name = words[0];
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  const proto::CommandSpec* spec = find_command(name);
  if (!spec) {
    return refuse(Reason::kUnknownCommand, proto::kTokenName, 0, "name",
                  "unknown command " + quote(words[0]) + "; known commands are STM, SVM and LED");
  }
  std::string usage = std::string(spec->name);
  for (uint32_t i = 0; i < spec->value_count; ++i) usage += std::string(" <") + spec->fields[i].name + ">";
  if (words.size() - 1 != spec->value_count) {
    return refuse(Reason::kBadLength, proto::kTokenLength, 0, "length",
                  std::string(spec->name) + " takes " + std::to_string(spec->value_count) + " values (" + usage +
                      "), got " + std::to_string(words.size() - 1),
                  spec->value_count, static_cast<uint32_t>(words.size() - 1));
  }
  std::array<uint32_t, proto::kMaxValues> values{};
  for (uint32_t i = 0; i < spec->value_count; ++i) {
    const std::optional<uint32_t> v = parse_number(words[1 + i]);
    if (!v) {
      return value_not_a_number(*spec, i, words[1 + i], 0);
    }
    values[i] = *v;
  }
  return validate(make_command(spec->id, values.data()));
}

}  // namespace hmc
