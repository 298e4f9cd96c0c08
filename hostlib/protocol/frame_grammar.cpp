// The host's reading of the frame grammar: docs/protocol.md's order of checks step by step, for
// any table of frame names. Works on string views over the caller's line and allocates only to
// explain a refusal.
#include "frame_grammar.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <utility>

namespace hmc::grammar {
namespace {

using proto::Reason;

// Enough tokens for a line of kLineMax '#' bytes.
constexpr std::size_t kMaxTokens = proto::kLineMax + 1;

// A three-letter name as one number (find() compares these); 0 for names of another length.
constexpr uint32_t packed_name(std::string_view name) {
  if (name.size() != 3) return 0;
  return static_cast<uint32_t>(static_cast<unsigned char>(name[0])) |
         static_cast<uint32_t>(static_cast<unsigned char>(name[1])) << 8 |
         static_cast<uint32_t>(static_cast<unsigned char>(name[2])) << 16;
}

// The grammar's view of one table entry; `action_field` is -1 for board frames.
constexpr Shape shape_of(std::string_view name, uint32_t value_count, const proto::FieldSpec* fields,
                         int action_field, uint32_t index) {
  Shape out{name, value_count, fields, action_field, packed_name(name), {}, {}, 0, false, {}, 0, index, nullptr};
  const auto put = [&out](char c) { out.head[out.head_size++] = c; };
  for (const char c : kStart) put(c);
  put('#');
  const uint32_t length = value_count + 1;  // at most kMaxValues + 1 = 10 fields
  if (length >= 10) put(static_cast<char>('0' + length / 10));
  put(static_cast<char>('0' + length % 10));
  put('#');
  for (const char c : name) put(c);
  put('#');
  for (uint32_t i = 0; i < value_count; ++i) {
    out.min[i] = fields[i].min;
    out.span[i] = fields[i].max - fields[i].min;
    if (fields[i].flags & proto::kPowerOfTwo) out.power_of_two |= 1u << i;
    if (fields[i].flags & proto::kSettingValue) out.ranged_by_setting = true;
  }
  return out;
}

template <std::size_t N>
constexpr std::array<Shape, N> shapes_of(const proto::CommandSpec (&specs)[N]) {
  std::array<Shape, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    out[i] = shape_of(specs[i].name, specs[i].value_count, specs[i].fields, specs[i].action_field,
                      static_cast<uint32_t>(i));
  }
  return out;
}

// VER as a board before protocol 7 (proto::Feature::kStepBudgets) sends it: no max_ramping_rate.
constexpr auto kVersionIndex = static_cast<uint32_t>(proto::BoardFrameId::kVersion);
constexpr Shape kVersionBefore7 = shape_of(proto::kBoardFrames[kVersionIndex].name, proto::kVersionValuesBefore7,
                                           proto::kVersionFields, -1, kVersionIndex);

template <std::size_t N>
constexpr std::array<Shape, N> shapes_of(const proto::BoardFrameSpec (&specs)[N]) {
  std::array<Shape, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    out[i] = shape_of(specs[i].name, specs[i].value_count, specs[i].fields, -1, static_cast<uint32_t>(i));
  }
  out[kVersionIndex].older = &kVersionBefore7;
  return out;
}

constexpr auto kCommandShapes = shapes_of(proto::kCommands);
constexpr auto kBoardFrameShapes = shapes_of(proto::kBoardFrames);

// Every name is three letters and every head fits its array (a longer name would need both
// find() and Shape::head to change).
template <std::size_t N>
constexpr bool three_letter_names(const std::array<Shape, N>& shapes) {
  for (const Shape& shape : shapes) {
    if (shape.key == 0 || shape.head_size < 8 || shape.head_size > 12) return false;
  }
  return true;
}
static_assert(three_letter_names(kCommandShapes) && three_letter_names(kBoardFrameShapes),
              "names are three letters and heads 8-12 bytes: find() and parse_canonical_frame() rely on it");

struct Token {
  std::string_view text;
  std::size_t offset = 0;  // in the line
};
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

bool has_leading_zero(std::string_view number) { return number.size() > 1 && number[0] == '0'; }

// Names token `token` of a frame of `k` tokens whose kind is `shape` (or unknown).
std::string token_name(const Shape* shape, std::size_t k, int token) {
  if (token == kNoToken) return "";
  const auto t = static_cast<std::size_t>(token);
  if (t == proto::kTokenStart) return "start";
  if (t == proto::kTokenLength) return "length";
  if (t == proto::kTokenName) return "name";
  if (k >= 2 && t == k - 1) return "end";
  if (k >= 5 && t == k - 2) return "checksum";
  const std::size_t value = t - proto::kTokenFirstValue;
  if (shape && value < shape->value_count) return shape->fields[value].name;
  return "value " + std::to_string(value + 1);
}

std::string range_text(const proto::FieldSpec& f) {
  std::string out = std::to_string(f.min) + "-" + std::to_string(f.max);
  if (f.flags & proto::kPowerOfTwo) out = "a power of two " + out;
  return out;
}

std::string sum_explanation(const uint32_t* values, uint32_t count) {
  if (count == 0) return "no values: the sum is 0";
  std::string sum_text;
  uint64_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) {
    if (i) sum_text += "+";
    sum_text += std::to_string(values[i]);
    sum += values[i];
  }
  return sum_text + " = " + std::to_string(sum) + ", mod 256 = " + std::to_string(sum % 256);
}

}  // namespace

constexpr ShapeTable kCommandTable{kCommandShapes.data(), kCommandShapes.size(), "command", "commands"};
constexpr ShapeTable kBoardFrameTable{kBoardFrameShapes.data(), kBoardFrameShapes.size(), "board frame",
                                      "board frames"};

bool is_blank_byte(char c) { return c == ' ' || c == '\t'; }
bool is_frame_byte(char c) { return c >= '!' && c <= '~'; }

std::string_view strip_blanks(std::string_view s, std::size_t& lead) {
  lead = 0;
  while (lead < s.size() && is_blank_byte(s[lead])) ++lead;
  std::size_t end = s.size();
  while (end > lead && is_blank_byte(s[end - 1])) --end;
  return s.substr(lead, end - lead);
}

std::optional<uint32_t> parse_number(std::string_view text) {
  if (text.empty() || text.size() > proto::kMaxDigits) return std::nullopt;
  uint64_t value = 0;
  const char* end = text.data() + text.size();
  auto [stop, err] = std::from_chars(text.data(), end, value, 10);
  if (err != std::errc() || stop != end || value > proto::kIntMax) return std::nullopt;
  return static_cast<uint32_t>(value);
}

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

const Shape* ShapeTable::find(std::string_view name) const {
  // Names are three letters (static_assert above): compared as one number each.
  const uint32_t key = packed_name(name);
  for (std::size_t i = 0; i < count && key != 0; ++i) {
    if (shapes[i].key == key) return &shapes[i];
  }
  return nullptr;
}

std::string ShapeTable::names() const {
  std::string out;
  for (std::size_t i = 0; i < count; ++i) {
    if (i > 0) out += i + 1 == count ? " and " : ", ";
    out += shapes[i].name;
  }
  return out;
}

Diagnostic refuse(Reason reason, int token, std::size_t offset, std::string field, std::string message,
                  uint32_t expected, uint32_t found) {
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

Diagnostic value_not_a_number(const Shape& shape, uint32_t i, std::string_view text, std::size_t offset) {
  return refuse(Reason::kBadNumber, static_cast<int>(proto::kTokenFirstValue + i), offset, shape.fields[i].name,
                std::string(shape.fields[i].name) + " is " + quote(text) +
                    ": expected an unsigned decimal number of 1-10 digits, at most 2147483647");
}

Diagnostic unknown_name(const ShapeTable& table, std::string_view name, std::size_t offset) {
  std::string message = std::string("unknown ") + table.noun + " " + quote(name) + "; known " + table.plural +
                        " are " + table.names() + " (case-sensitive)";
  const ShapeTable& other = &table == &command_shapes() ? board_frame_shapes() : command_shapes();
  if (other.find(name) != nullptr) {
    message += "; " + std::string(name) + " is one of the " + other.plural +
               (&other == &command_shapes() ? " (host to board)" : " (board to host)");
  }
  return refuse(Reason::kUnknownCommand, proto::kTokenName, offset, "name", std::move(message));
}

uint32_t sum_of(const uint32_t* values, uint32_t count) {
  uint32_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) sum = (sum + (values[i] & 0xFFu)) & 0xFFu;
  return sum;
}

uint32_t crc_of(std::string_view bytes) {
  return proto::crc16(reinterpret_cast<const uint8_t*>(bytes.data()), static_cast<uint32_t>(bytes.size()));
}

Result<Frame, Diagnostic> parse_frame(std::string_view line, proto::ChecksumMode mode, const ShapeTable& table) {
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
  const Shape* named = table.find(name_text);
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
  if (!named) return unknown_name(table, name_text, tokens[proto::kTokenName].offset);
  const Shape& shape = named->older && *len == named->older->value_count + 1u ? *named->older : *named;
  // 11. Length agrees with the frame's kind.
  if (*len != shape.value_count + 1u) {
    return refuse(Reason::kBadLength, proto::kTokenLength, len_token.offset, "length",
                  std::string(shape.name) + " has " + std::to_string(shape.value_count + 1) +
                      " fields (its name and " + std::to_string(shape.value_count) + " values" +
                      (shape.older ? "; " + std::to_string(shape.older->value_count + 1) + " from an older board"
                                   : std::string()) +
                      ") but the length field says " + std::to_string(*len),
                  shape.value_count + 1u, *len);
  }
  // 12. Value numbers.
  Frame out;
  out.shape = &shape;
  out.canonical = lead == 0 && frame.size() == line.size() && !has_leading_zero(len_token.text);
  for (uint32_t i = 0; i < shape.value_count; ++i) {
    const Token& t = tokens[proto::kTokenFirstValue + i];
    const std::optional<uint32_t> v = parse_number(t.text);
    if (!v) return value_not_a_number(shape, i, t.text, t.offset);
    out.values[i] = *v;
    out.offsets[i] = t.offset;
    out.canonical = out.canonical && !has_leading_zero(t.text);
  }
  // 13. Checksum number: 0-255, or 0-65535 in CRC-16 mode.
  const bool crc_mode = mode == proto::ChecksumMode::kCrc16;
  const int checksum_token = static_cast<int>(k - 2);
  const Token& cs_token = tokens[k - 2];
  const std::string_view covered = frame.substr(0, cs_token.offset - lead);  // 'S' of STX to the '#'
  const uint32_t max = crc_mode ? proto::kCrcMax : proto::kChecksumMax;
  const std::optional<uint32_t> given = parse_number(cs_token.text);
  if (!given) {
    return refuse(Reason::kBadNumber, checksum_token, cs_token.offset, "checksum",
                  "checksum is " + quote(cs_token.text) + ": expected a decimal number 0-" + std::to_string(max) +
                      (crc_mode ? " written as exactly " + std::to_string(proto::kCrcDigits) + " digits" : ""));
  }
  if (crc_mode && cs_token.text.size() != proto::kCrcDigits) {
    // A CRC field of fixed width: no digit can move across the '#' into it unnoticed.
    return refuse(Reason::kBadNumber, checksum_token, cs_token.offset, "checksum",
                  "checksum is " + quote(cs_token.text) + " (" + std::to_string(cs_token.text.size()) +
                      " digits): in CRC-16 mode the checksum is exactly " + std::to_string(proto::kCrcDigits) +
                      " digits, zero-padded" +
                      (*given <= max ? " ('" + crc_text(*given) + "' for " + std::to_string(*given) + ")" : "") +
                      (*given == sum_of(out.values.data(), shape.value_count)
                           ? "; this is the seed's sum, but CRC-16 mode is in force"
                           : ""));
  }
  if (*given > max) {
    std::string message = "checksum is " + std::to_string(*given) + ": a checksum is 0-" + std::to_string(max);
    if (crc_mode) {
      message += " (a CRC-16)";
    } else if (*given == crc_of(covered)) {
      message += " (this is the frame's CRC-16, but the seed's sum is in force until CRC 1 is acknowledged)";
    }
    return refuse(Reason::kOutOfRange, checksum_token, cs_token.offset, "checksum", std::move(message), 0, *given);
  }
  // 14. Checksum.
  const uint32_t sum = sum_of(out.values.data(), shape.value_count);
  const uint32_t want = crc_mode ? crc_of(covered) : sum;
  if (*given != want) {
    std::string message =
        "checksum is " + std::to_string(*given) + " where " + std::to_string(want) + " was expected (";
    if (crc_mode) {
      message += "CRC-16 of " + quote(covered) + ")";
      if (*given == sum) message += "; this is the seed's sum, but CRC-16 mode is in force";
    } else {
      message += sum_explanation(out.values.data(), shape.value_count) + ")";
      if (*given == crc_of(covered)) message += "; this is the frame's CRC-16, but the seed's sum is in force";
    }
    return refuse(Reason::kChecksumMismatch, checksum_token, cs_token.offset, "checksum", std::move(message), want,
                  *given);
  }
  // In CRC-16 mode the padding is the canonical form (its width was checked at step 13).
  out.canonical = out.canonical && (crc_mode || !has_leading_zero(cs_token.text));
  return out;
}

namespace {

// Reads the run of digits at `p` into `value` and returns where it stops. The line's "#ETX"
// stops every run before the line ends, so the loop needs no bound of its own; a run longer
// than 9 digits may wrap `value`, and the caller refuses it for its length.
inline const char* read_digits(const char* p, uint32_t& value) {
  value = 0;
  for (unsigned digit = static_cast<unsigned char>(*p) - '0'; digit <= 9;
       digit = static_cast<unsigned char>(*++p) - '0') {
    value = value * 10 + digit;
  }
  return p;
}

// A canonical number of 1 to `max_digits` digits (at most 9: ten-digit values are left to the
// step-by-step reading, which also bounds them), no leading zero.
inline bool canonical_digits(const char* first, const char* stop, std::ptrdiff_t max_digits) {
  const std::ptrdiff_t digits = stop - first;
  return digits >= 1 && digits <= max_digits && (digits == 1 || *first != '0');
}

// Eight bytes, for comparing them at once.
inline uint64_t load8(const char* p) {
  uint64_t x = 0;
  std::memcpy(&x, p, sizeof x);
  return x;
}

}  // namespace

const Shape* parse_canonical_frame(std::string_view line, proto::ChecksumMode mode, const ShapeTable& table,
                                   std::array<uint32_t, proto::kMaxValues>& values) {
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() > proto::kLineMax || line.size() < 12 ||
      line.compare(line.size() - kEnd.size(), kEnd.size(), kEnd) != 0 || line[line.size() - kEnd.size() - 1] != '#') {
    return nullptr;
  }
  const char* const end = line.data() + line.size() - kEnd.size() - 1;  // the '#' before ETX
  // "STX#<length>#<NAME>#": the name is the three bytes after "STX#" and a one-digit length,
  // and the whole head must be its shape's (a frame of 10 fields, VER, or an older shape's
  // length does not match: parse_frame() reads those). The head is 8-12 bytes (static_assert
  // above) and the line at least 12: two overlapping loads of eight compare it.
  const Shape* shape = table.find(line.substr(kStart.size() + 3, 3));
  if (shape == nullptr || load8(line.data()) != load8(shape->head.data()) ||
      load8(line.data() + shape->head_size - 8) != load8(shape->head.data() + shape->head_size - 8)) {
    return nullptr;
  }
  // Values: each a canonical run of digits and a '#'. Reading stays within the line: a run
  // stops at the '#' before ETX or at 'E', and a value that should follow the last '#' finds
  // 'E' and no digits.
  const char* p = line.data() + shape->head_size;
  uint32_t sum = 0;
  uint32_t outside = 0;  // outside_own_ranges(), on the way
  for (uint32_t i = 0; i < shape->value_count; ++i) {
    uint32_t value = 0;
    const char* const first = p;
    p = read_digits(p, value);
    if (*p != '#' || !canonical_digits(first, p, 9)) return nullptr;
    values[i] = value;
    sum += value;
    outside |= outside_own_range(*shape, i, value);
    ++p;
  }
  uint32_t given = 0;
  const char* const checksum_at = p;
  p = read_digits(p, given);
  if (p != end) return nullptr;
  if (mode == proto::ChecksumMode::kCrc16) {
    // Exactly kCrcDigits digits, zero-padded.
    const std::string_view covered(line.data(), static_cast<std::size_t>(checksum_at - line.data()));
    if (p - checksum_at != proto::kCrcDigits || given != crc_of(covered)) return nullptr;
  } else if (!canonical_digits(checksum_at, p, 3) || given != (sum & 0xFFu)) {
    return nullptr;
  }
  return passes_plainly(*shape, values.data(), outside) ? shape : nullptr;
}

namespace {

// The setting whose range a setting value (kSettingValue, after a setting id) must lie in.
const proto::SettingSpec* setting_of(const proto::FieldSpec& f, const uint32_t* values, uint32_t i) {
  if (!(f.flags & proto::kSettingValue) || i == 0 || values[i - 1] < 1 || values[i - 1] > proto::kSettingCount) {
    return nullptr;
  }
  return &proto::kSettings[values[i - 1] - 1];
}

}  // namespace

ValueFault find_fault(const Shape& shape, const uint32_t* values) {
  // The action field precedes every field whose check depends on it, and a setting's id the
  // value it ranges, so checking left to right has vouched for them when they are needed.
  const bool has_action = shape.action_field >= 0;
  const uint32_t action = has_action ? values[static_cast<std::size_t>(shape.action_field)] : 0;
  const bool stopping = has_action && action == proto::kActionStop;
  const bool homing = has_action && action == proto::kActionHome;
  for (uint32_t i = 0; i < shape.value_count; ++i) {
    const proto::FieldSpec& f = shape.fields[i];
    const uint32_t v = values[i];
    // Most fields: within their own range, whatever the exemptions below.
    if ((f.flags & (proto::kSettingValue | proto::kPowerOfTwo)) == 0 && v >= f.min && v <= f.max) continue;
    if ((f.flags & proto::kUncheckedOnStop) && stopping) continue;
    if (v == 0 && (f.flags & proto::kZeroAllowedOnHome) && homing) continue;
    const proto::SettingSpec* setting = setting_of(f, values, i);
    const uint32_t min = setting != nullptr ? setting->min : f.min;
    const uint32_t max = setting != nullptr ? setting->max : f.max;
    if (v >= min && v <= max && (!(f.flags & proto::kPowerOfTwo) || proto::is_power_of_two(v))) continue;
    return {proto::Reason::kOutOfRange, i};
  }
  if (homing && !proto::motor_has_switches(values[0])) return {proto::Reason::kNoSwitch, 0};
  return {proto::Reason::kOk, 0};
}

std::optional<Diagnostic> check_values(const Shape& shape, const uint32_t* values, const std::size_t* offsets) {
  const ValueFault fault = find_fault(shape, values);
  const uint32_t i = fault.index;
  if (fault.reason == proto::Reason::kNoSwitch) {
    return refuse(proto::Reason::kNoSwitch, proto::kTokenFirstValue, offsets[0], shape.fields[0].name,
                  "motor " + std::to_string(values[0]) +
                      " has no limit switch to home against; only motors with switches (1 and 2) can home");
  }
  if (fault.reason != proto::Reason::kOutOfRange) return std::nullopt;
  const proto::FieldSpec& f = shape.fields[i];
  std::string message = std::string(f.name) + " is " + std::to_string(values[i]) + ": expected ";
  if (const proto::SettingSpec* setting = setting_of(f, values, i)) {
    message += std::to_string(setting->min) + "-" + std::to_string(setting->max) + " for setting " +
               std::to_string(values[i - 1]) + " (" + setting->name + ")";
  } else {
    message += range_text(f);
  }
  if (f.flags & proto::kZeroAllowedOnHome) message += " (0 only when homing)";
  return refuse(proto::Reason::kOutOfRange, static_cast<int>(proto::kTokenFirstValue + i), offsets[i], f.name,
                std::move(message), 0, values[i]);
}

std::array<std::size_t, proto::kMaxValues> canonical_offsets(const Shape& shape, const uint32_t* values) {
  // "STX#<len>#<NAME>#v1#v2...".
  std::array<std::size_t, proto::kMaxValues> offsets{};
  const auto digits = [](uint32_t n) {
    std::size_t count = 1;
    while (n >= 10) {
      n /= 10;
      ++count;
    }
    return count;
  };
  std::size_t at = kStart.size() + 1 + digits(shape.value_count + 1) + 1 + shape.name.size() + 1;
  for (uint32_t i = 0; i < shape.value_count; ++i) {
    offsets[i] = at;
    at += digits(values[i]) + 1;
  }
  return offsets;
}

}  // namespace hmc::grammar
