// The host codec: decode with diagnostics, validate, lint, encode, and typed-input parsing.
//
// decode() follows docs/protocol.md's order of checks step by step (frame_grammar.h holds the
// steps both directions share) with the command table's names, then the ranges and rules.
#include "hmc/codec.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <optional>

#include "frame_grammar.h"

namespace hmc {
namespace {

using proto::Reason;
namespace g = grammar;

const g::Shape& shape_of(const Command& command) {
  return g::command_shapes().shapes[static_cast<std::size_t>(command_id(command))];
}

Command command_of(const g::Shape& shape, const uint32_t* values) {
  return make_command(static_cast<proto::CommandId>(g::command_shapes().index_of(shape)), values);
}

std::string usage_of(const g::Shape& shape) {
  std::string usage(shape.name);
  for (uint32_t i = 0; i < shape.value_count; ++i) usage += std::string(" <") + shape.fields[i].name + ">";
  return usage;
}

// The refusal of values find_fault() found wrong, explained at their canonical offsets.
Diagnostic refusal_of(const g::Shape& shape, const uint32_t* values) {
  const auto offsets = g::canonical_offsets(shape, values);
  return std::move(*g::check_values(shape, values, offsets.data()));
}

// The fields of each command that the spec's table gives advice for, as bits (STM's delay_us
// alone, today): lint() looks at those alone.
constexpr uint32_t advised_fields(const proto::CommandSpec& spec) {
  uint32_t bits = 0;
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    if (spec.fields[i].advised_min != 0 || spec.fields[i].advised_max != 0) bits |= 1u << i;
  }
  return bits;
}

template <std::size_t... I>
constexpr std::array<uint32_t, sizeof...(I)> advice_table(std::index_sequence<I...>) {
  return {advised_fields(proto::kCommands[I])...};
}
constexpr auto kAdvisedFields = advice_table(std::make_index_sequence<proto::kCommandCount>{});

// Whether value i lies outside its field's advice, where a stop or a home does not exempt it.
bool outside_advice(const proto::CommandSpec& spec, const uint32_t* values, uint32_t i) {
  const proto::FieldSpec& f = spec.fields[i];
  if (values[i] >= f.advised_min && values[i] <= f.advised_max) return false;
  const uint32_t action = spec.action_field >= 0 ? values[spec.action_field] : proto::kActionForward;
  if (action == proto::kActionStop && (f.flags & proto::kUncheckedOnStop)) return false;
  return !(values[i] == 0 && (f.flags & proto::kZeroAllowedOnHome) && action == proto::kActionHome);
}

// Limits that are not ordered switch soft limits off; only all zeros says so plainly.
bool switches_limits_off(const SoftLimits& l) {
  const bool all_zero = l.low_sign == 0 && l.low == 0 && l.high_sign == 0 && l.high == 0;
  return !all_zero && l.low_position() >= l.high_position();
}

// Whether lint() has anything to say, asked before any message is made.
bool has_lint(const proto::CommandSpec& spec, const uint32_t* values, const Command& command) {
  for (uint32_t bits = kAdvisedFields[static_cast<std::size_t>(spec.id)]; bits != 0; bits &= bits - 1) {
    if (outside_advice(spec, values, static_cast<uint32_t>(__builtin_ctz(bits)))) return true;
  }
  const auto* limits = std::get_if<SoftLimits>(&command);
  return limits != nullptr && switches_limits_off(*limits);
}

// lint() of a command whose values are at hand.
std::vector<Warning> lint_values(const proto::CommandSpec& spec, const uint32_t* values, const Command& command) {
  std::vector<Warning> out;
  for (uint32_t bits = kAdvisedFields[static_cast<std::size_t>(spec.id)]; bits != 0; bits &= bits - 1) {
    const auto i = static_cast<uint32_t>(__builtin_ctz(bits));
    if (!outside_advice(spec, values, i)) continue;
    const proto::FieldSpec& f = spec.fields[i];
    out.push_back({f.name, std::string(f.name) + " " + std::to_string(values[i]) + " is outside the spec's advised " +
                               std::to_string(f.advised_min) + "-" + std::to_string(f.advised_max) +
                               (values[i] < f.advised_min ? " (the motor may stall or skip steps)"
                                                          : " (very slow)")});
  }
  const auto* l = std::get_if<SoftLimits>(&command);
  if (l != nullptr && switches_limits_off(*l)) {
    out.push_back({"high", "low " + position_text(l->low_position()) + " is not below high " +
                               position_text(l->high_position()) +
                               ": this switches the soft limits off (LIM m 0 0 0 0 says so plainly)"});
  }
  return out;
}

// The accepted command of a frame that passed every check, made where the caller receives it:
// moving a command just written costs more than writing it.
Result<Decoded, Diagnostic> accepted(const g::Shape& shape, const uint32_t* values, bool canonical) {
  Result<Decoded, Diagnostic> out{std::in_place};
  Decoded& decoded = *out;
  const auto id = static_cast<proto::CommandId>(g::command_shapes().index_of(shape));
  set_command(decoded.command, id, values);
  decoded.canonical = canonical;
  const proto::CommandSpec& spec = proto::command_spec(id);
  if (has_lint(spec, values, decoded.command)) decoded.warnings = lint_values(spec, values, decoded.command);
  return out;
}

}  // namespace

bool is_blank(std::string_view line) {
  return std::all_of(line.begin(), line.end(), g::is_blank_byte);
}

uint32_t checksum(const Command& command, proto::ChecksumMode mode) {
  const CommandValues v = command_values(command);
  return g::checksum_of(shape_of(command), v.values.data(), mode);
}

Result<Decoded, Diagnostic> decode(std::string_view line, proto::ChecksumMode mode) {
  // The common case in one pass; anything else (a refusal, blanks, leading zeros, a value the
  // rules decide) is judged and explained step by step below.
  std::array<uint32_t, proto::kMaxValues> values{};
  if (const g::Shape* shape = g::parse_canonical_frame(line, mode, g::command_shapes(), values)) {
    return accepted(*shape, values.data(), true);
  }
  auto frame = g::parse_frame(line, mode, g::command_shapes());
  if (!frame) return frame.error();
  // 15-16. Ranges and rules.
  if (auto refusal = g::check_values(*frame->shape, frame->values.data(), frame->offsets.data())) {
    return std::move(*refusal);
  }
  return accepted(*frame->shape, frame->values.data(), frame->canonical);
}

Result<Command, Diagnostic> validate(const Command& command) {
  const g::Shape& shape = shape_of(command);
  const CommandValues v = command_values(command);
  if (g::values_valid(shape, v.values.data())) return command;
  return refusal_of(shape, v.values.data());
}

std::vector<Warning> lint(const Command& command) {
  return lint_values(command_spec(command), command_values(command).values.data(), command);
}

Result<std::string, Diagnostic> encode(const Command& command, proto::ChecksumMode mode) {
  FrameText text;
  auto written = encode_into(command, text, mode);
  if (!written) return written.error();
  return std::string(text.view());
}

Result<std::size_t, Diagnostic> encode_into(const Command& command, FrameText& out, proto::ChecksumMode mode) {
  const g::Shape& shape = shape_of(command);
  const CommandValues v = command_values(command);
  // Written first and checked on the way: a refused command leaves bytes but no frame.
  char* const first = out.bytes.data();
  uint32_t outside = 0;
  char* const end = g::write_frame_bytes(first, shape, v.values.data(), mode, outside);
  if (!g::passes_plainly(shape, v.values.data(), outside) &&
      g::find_fault(shape, v.values.data()).reason != Reason::kOk) {
    out.size = 0;
    return refusal_of(shape, v.values.data());
  }
  out.size = static_cast<std::size_t>(end - first);
  return out.size;
}

Result<Command, Diagnostic> parse_input(std::string_view text, proto::ChecksumMode mode) {
  std::size_t lead = 0;
  const std::string_view body = g::strip_blanks(text, lead);
  if (body.empty() || body.front() != '[') {
    auto decoded = decode(text, mode);
    if (!decoded) return decoded.error();
    return decoded->command;
  }
  // Command-set notation: [#NAME#v1#...#vn], held to the frame's length limit.
  if (body.size() > proto::kLineMax) {
    return g::refuse(Reason::kLineTooLong, kNoToken, lead + proto::kLineMax, "",
                     "command-set notation is " + std::to_string(body.size()) + " bytes long; at most " +
                         std::to_string(proto::kLineMax) + " fit on a line");
  }
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (!g::is_frame_byte(body[i])) {
      return g::refuse(Reason::kBadByte, kNoToken, lead + i, "",
                       "byte " + g::quote(body.substr(i, 1)) + " at offset " + std::to_string(lead + i) +
                           " cannot appear in command-set notation");
    }
  }
  if (body.back() != ']') {
    return g::refuse(Reason::kBadEnd, kNoToken, lead + body.size() - 1, "end",
                     "command-set notation must end with ']'");
  }
  if (body.size() < 2 || body[1] != '#') {
    return g::refuse(Reason::kBadStart, kNoToken, lead, "start",
                     "command-set notation must start with '[#', as in [#SVM#1#135]");
  }
  // Split "NAME#v1#...#vn" at every '#'.
  const std::string_view inner = body.substr(2, body.size() - 3);
  std::vector<std::string_view> words;
  std::vector<std::size_t> offsets;
  for (std::size_t begin = 0;;) {
    const std::size_t hash = inner.find('#', begin);
    const std::size_t end = hash == std::string_view::npos ? inner.size() : hash;
    words.push_back(inner.substr(begin, end - begin));
    offsets.push_back(lead + 2 + begin);
    if (hash == std::string_view::npos) break;
    begin = hash + 1;
  }
  const g::Shape* shape = g::command_shapes().find(words[0]);
  if (!shape) return g::unknown_name(g::command_shapes(), words[0], offsets[0]);
  if (words.size() - 1 != shape->value_count) {
    return g::refuse(Reason::kBadLength, proto::kTokenLength, offsets[0], "length",
                     std::string(shape->name) + " takes " + std::to_string(shape->value_count) + " values (" +
                         usage_of(*shape) + "), got " + std::to_string(words.size() - 1),
                     shape->value_count, static_cast<uint32_t>(words.size() - 1));
  }
  std::array<uint32_t, proto::kMaxValues> values{};
  std::array<std::size_t, proto::kMaxValues> value_offsets{};
  for (uint32_t i = 0; i < shape->value_count; ++i) {
    const std::optional<uint32_t> v = g::parse_number(words[1 + i]);
    if (!v) return g::value_not_a_number(*shape, i, words[1 + i], offsets[1 + i]);
    values[i] = *v;
    value_offsets[i] = offsets[1 + i];
  }
  if (auto refusal = g::check_values(*shape, values.data(), value_offsets.data())) return std::move(*refusal);
  return command_of(*shape, values.data());
}

Result<Command, Diagnostic> command_from_words(const std::vector<std::string>& words) {
  const g::ShapeTable& table = g::command_shapes();
  if (words.empty()) {
    return g::refuse(Reason::kUnknownCommand, proto::kTokenName, 0, "name",
                     "no command given: expected one of " + table.names());
  }
  std::string name = words[0];
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  const g::Shape* shape = table.find(name);
  if (!shape) {
    return g::refuse(Reason::kUnknownCommand, proto::kTokenName, 0, "name",
                     "unknown command " + g::quote(words[0]) + "; known commands are " + table.names());
  }
  if (words.size() - 1 != shape->value_count) {
    return g::refuse(Reason::kBadLength, proto::kTokenLength, 0, "length",
                     std::string(shape->name) + " takes " + std::to_string(shape->value_count) + " values (" +
                         usage_of(*shape) + "), got " + std::to_string(words.size() - 1),
                     shape->value_count, static_cast<uint32_t>(words.size() - 1));
  }
  std::array<uint32_t, proto::kMaxValues> values{};
  for (uint32_t i = 0; i < shape->value_count; ++i) {
    const std::optional<uint32_t> v = g::parse_number(words[1 + i]);
    if (!v) return g::value_not_a_number(*shape, i, words[1 + i], 0);
    values[i] = *v;
  }
  return validate(command_of(*shape, values.data()));
}

Result<Command, Diagnostic> command_from_text(std::string_view text, proto::ChecksumMode mode) {
  if (text.find('#') != std::string_view::npos) return parse_input(text, mode);
  std::vector<std::string> words;
  for (std::size_t at = 0; at < text.size();) {
    if (g::is_blank_byte(text[at])) {
      ++at;
      continue;
    }
    std::size_t end = at;
    while (end < text.size() && !g::is_blank_byte(text[end])) ++end;
    words.emplace_back(text.substr(at, end - at));
    at = end;
  }
  return command_from_words(words);
}

}  // namespace hmc
