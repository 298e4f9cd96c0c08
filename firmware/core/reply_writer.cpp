// Formats reply frames (reply_writer.h) with integer-only decimal conversion.
#include "reply_writer.h"

namespace hmc::fw {
namespace {

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

uint32_t put_text(uint8_t* out, uint32_t at, const char* text) {
  while (*text != '\0') out[at++] = static_cast<uint8_t>(*text++);
  return at;
}

}  // namespace

void write_frame(hal::SerialPort& port, const char* name, const uint32_t* values, uint32_t count) {
  if (count > proto::kMaxValues) count = proto::kMaxValues;
  uint8_t line[proto::kLineMax];
  uint32_t at = put_text(line, 0, "STX#");
  at = put_number(line, at, count + 1u);
  line[at++] = '#';
  at = put_text(line, at, name);
  uint32_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) {
    line[at++] = '#';
    at = put_number(line, at, values[i]);
    sum += values[i];
  }
  line[at++] = '#';
  at = put_number(line, at, sum & 0xFFu);
  at = put_text(line, at, "#ETX\n");
  port.write(line, at);
}

void write_ack(hal::SerialPort& port) { write_frame(port, proto::kReplyAccepted, nullptr, 0); }

void write_nak(hal::SerialPort& port, proto::Reason reason, uint8_t token, uint8_t offset) {
  const uint32_t values[] = {static_cast<uint32_t>(reason), token, offset};
  write_frame(port, proto::kReplyRefused, values, 3);
}

}  // namespace hmc::fw
