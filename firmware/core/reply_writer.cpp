// Formats reply frames (reply_writer.h) with integer-only decimal conversion.
#include "reply_writer.h"

namespace hmc::fw {
namespace {

constexpr bool board_frames_fit() {
  for (const proto::BoardFrameSpec& frame : proto::kBoardFrames) {
    if (frame.value_count > proto::kMaxValues) return false;
  }
  return true;
}
static_assert(board_frames_fit(), "every board frame fits the line buffer (kMaxValues)");

// Appends the decimal digits of `value`; returns the new length.
uint32_t put_number(uint8_t* out, uint32_t at, uint32_t value) {
  uint8_t digits[proto::kMaxDigits];
  uint32_t n = 0;
  do {
    const uint32_t tenth = value / 10u;
    digits[n++] = static_cast<uint8_t>('0' + (value - tenth * 10u));
    value = tenth;
  } while (value != 0 && n < proto::kMaxDigits);
  while (n > 0) out[at++] = digits[--n];
  return at;
}

// Appends `value` as exactly `width` decimal digits, zero-padded on the left (value < 10^width).
uint32_t put_padded(uint8_t* out, uint32_t at, uint32_t value, uint32_t width) {
  for (uint32_t i = width; i > 0; --i) {
    const uint32_t tenth = value / 10u;
    out[at + i - 1] = static_cast<uint8_t>('0' + (value - tenth * 10u));
    value = tenth;
  }
  return at + width;
}

uint32_t put_text(uint8_t* out, uint32_t at, const char* text) {
  while (*text != '\0') out[at++] = static_cast<uint8_t>(*text++);
  return at;
}

}  // namespace

void write_frame(hal::SerialPort& port, proto::BoardFrameId id, const uint32_t* values,
                 proto::ChecksumMode mode) {
  const proto::BoardFrameSpec& spec = proto::board_frame_spec(id);
  uint8_t line[proto::kLineMax];
  uint32_t at = put_text(line, 0, "STX#");
  at = put_number(line, at, spec.value_count + 1u);
  line[at++] = '#';
  at = put_text(line, at, spec.name);
  uint32_t sum = 0;
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    line[at++] = '#';
    at = put_number(line, at, values[i]);
    sum += values[i];
  }
  line[at++] = '#';
  if (mode == proto::ChecksumMode::kCrc16) {
    at = put_padded(line, at, proto::crc16(line, at), proto::kCrcDigits);
  } else {
    at = put_number(line, at, sum & 0xFFu);
  }
  at = put_text(line, at, "#ETX\n");
  port.write(line, at);
}

void write_ack(hal::SerialPort& port, proto::ChecksumMode mode) {
  write_frame(port, proto::BoardFrameId::kAck, nullptr, mode);
}

void write_nak(hal::SerialPort& port, proto::Reason reason, uint8_t token, uint8_t offset,
               proto::ChecksumMode mode) {
  const uint32_t values[] = {static_cast<uint32_t>(reason), token, offset};
  write_frame(port, proto::BoardFrameId::kNak, values, mode);
}

}  // namespace hmc::fw
