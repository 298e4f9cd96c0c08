// The frame grammar of docs/protocol.md as the host reads it, for both directions: host ->
// board commands (decode) and board -> host frames (decode_board_frame) share it, each with its
// own table of names. Internal to libhmc; the public API is codec.h and board_frame.h.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hmc/crc16.h"
#include "hmc/protocol_facts.h"
#include "hmc/codec.h"
#include "hmc/result.h"

namespace hmc::grammar {

// A frame begins and ends with these.
constexpr std::string_view kStart = "STX";
constexpr std::string_view kEnd = "ETX";

// What the grammar needs of one kind of frame: a CommandSpec or a BoardFrameSpec.
struct Shape {
  std::string_view name;
  uint32_t value_count;
  const proto::FieldSpec* fields;
  int action_field;  // -1: none
  uint32_t key;      // a three-letter name packed into a number (0: another length)
  // The fields' own ranges as value - min <= span, for the check without a branch per value.
  std::array<uint32_t, proto::kMaxValues> min;
  std::array<uint32_t, proto::kMaxValues> span;
  uint32_t power_of_two;   // bit i: value i must be a power of two
  bool ranged_by_setting;  // a value's range is given by the setting the one before names
  // The frame up to its first value, "STX#6#STM#", which the writer copies in one go.
  std::array<char, 16> head;
  uint32_t head_size;
  uint32_t index;      // its entry in its table: the CommandId or BoardFrameId
  const Shape* older;  // the same frame with fewer values, as a board older than a feature sends it
};

// The frames one side may send, and how messages call them.
struct ShapeTable {
  const Shape* shapes;
  std::size_t count;
  const char* noun;    // "command", "board frame"
  const char* plural;  // "commands", "board frames"

  const Shape* find(std::string_view name) const;
  std::size_t index_of(const Shape& shape) const { return shape.index; }
  std::string names() const;  // "STM, SVM and LED"
};
extern const ShapeTable kCommandTable;     // proto::kCommands, in CommandId order
extern const ShapeTable kBoardFrameTable;  // proto::kBoardFrames, in BoardFrameId order
inline const ShapeTable& command_shapes() { return kCommandTable; }
inline const ShapeTable& board_frame_shapes() { return kBoardFrameTable; }

// A frame that passed steps 1-14 of the order of checks.
struct Frame {
  const Shape* shape = nullptr;
  std::array<uint32_t, proto::kMaxValues> values{};
  std::array<std::size_t, proto::kMaxValues> offsets{};  // in the line
  bool canonical = true;
};

bool is_blank_byte(char c);
bool is_frame_byte(char c);
std::string_view strip_blanks(std::string_view s, std::size_t& lead);
// 1-10 decimal digits up to INT_MAX; anything else is not a number.
std::optional<uint32_t> parse_number(std::string_view text);
// Text in single quotes, bytes outside printable ASCII as \xHH.
std::string quote(std::string_view s);

Diagnostic refuse(proto::Reason reason, int token, std::size_t offset, std::string field, std::string message,
                  uint32_t expected = 0, uint32_t found = 0);
Diagnostic value_not_a_number(const Shape& shape, uint32_t i, std::string_view text, std::size_t offset);
Diagnostic unknown_name(const ShapeTable& table, std::string_view name, std::size_t offset);

// Steps 1-14: length, blanks, bytes, start, end, lengths, name, numbers, checksum. A line may
// end in one LF, CRLF or CR, which is removed. A blank line is refused as bad_start. A frame
// with the value count of its shape's `older` form gets that shape.
Result<Frame, Diagnostic> parse_frame(std::string_view line, proto::ChecksumMode mode, const ShapeTable& table);

// Steps 1-16 in one pass for the common case: a canonical frame (nothing around it, no leading
// zeros, values of at most 9 digits) whose values pass plainly (passes_plainly() below). Returns
// its shape and fills `values`; returns nullptr for anything else, which parse_frame() and
// find_fault() then judge and explain. It never accepts a line that those refuse or read
// differently (the host_decode fuzzer checks this).
const Shape* parse_canonical_frame(std::string_view line, proto::ChecksumMode mode, const ShapeTable& table,
                                   std::array<uint32_t, proto::kMaxValues>& values);

// Steps 15-16: ranges left to right under the action's exemptions and the setting's range, then
// the switch rule. The first value that fails, and why (kOutOfRange or kNoSwitch; kOk: none).
struct ValueFault {
  proto::Reason reason;
  uint32_t index;  // of the value
};
ValueFault find_fault(const Shape& shape, const uint32_t* values);
// Whether values pass without find_fault()'s rules: every value within its field's own range
// (`outside`, non-zero when one is not) and a power of two where it must be, no value ranged by a
// setting, and no home (the switch rule). Decided without a branch per value.
inline bool passes_plainly(const Shape& shape, const uint32_t* values, uint32_t outside) {
  for (uint32_t bits = shape.power_of_two; bits != 0; bits &= bits - 1) {
    const uint32_t v = values[__builtin_ctz(bits)];
    outside |= v & (v - 1);
  }
  const bool homing = shape.action_field >= 0 && values[shape.action_field] == proto::kActionHome;
  return outside == 0 && !shape.ranged_by_setting && !homing;
}
// 1 when `value` lies outside the own range of field i, else 0: to be or-ed without a branch.
inline uint32_t outside_own_range(const Shape& shape, uint32_t i, uint32_t value) {
  return static_cast<uint32_t>(value - shape.min[i] > shape.span[i]);
}
// Non-zero when a value lies outside its field's own range. The values are read one by one
// (value_count of them): they were written so just before, and reading several at once would
// wait for those writes to reach memory.
inline uint32_t outside_own_ranges(const Shape& shape, const uint32_t* values) {
  uint32_t outside = 0;
  for (uint32_t i = 0; i < shape.value_count; ++i) outside |= outside_own_range(shape, i, values[i]);
  return outside;
}
// Whether find_fault() finds nothing, the common case decided by passes_plainly().
inline bool values_valid(const Shape& shape, const uint32_t* values) {
  return passes_plainly(shape, values, outside_own_ranges(shape, values)) ||
         find_fault(shape, values).reason == proto::Reason::kOk;
}
// find_fault() explained: `offsets[i]` is where value i starts in the text the diagnostic
// refers to. Nothing when the values pass.
std::optional<Diagnostic> check_values(const Shape& shape, const uint32_t* values, const std::size_t* offsets);

// Where each value starts in the canonical frame of these values.
std::array<std::size_t, proto::kMaxValues> canonical_offsets(const Shape& shape, const uint32_t* values);

// The checksum field of the canonical frame of these values.
uint32_t checksum_of(const Shape& shape, const uint32_t* values, proto::ChecksumMode mode);
// A CRC-16 as the checksum field writes it: exactly proto::kCrcDigits digits, zero-padded.
std::string crc_text(uint32_t crc);
// The canonical frame of these values, checksum in `mode`, no line end. Does not check ranges.
std::string write_frame(const Shape& shape, const uint32_t* values, proto::ChecksumMode mode);
// The same, written at `w`, which has FrameText::kRoom bytes; returns where the frame ends.
// `outside` gets outside_own_ranges(), found on the way.
char* write_frame_bytes(char* w, const Shape& shape, const uint32_t* values, proto::ChecksumMode mode,
                        uint32_t& outside);

// The seed's checksum: the values' sum mod 256.
uint32_t sum_of(const uint32_t* values, uint32_t count);
// The CRC-16 checksum of a frame's bytes from the 'S' of STX through the '#' before the checksum.
uint32_t crc_of(std::string_view bytes);

}  // namespace hmc::grammar
