// Tests of the reply frames and of FrameParser::token_offset, which locates a rule refusal's
// token in the line the parser accepted.
#include "core/reply_writer.h"

#include <catch2/catch.hpp>

#include <iterator>
#include <string>

#include "core/frame_parser.h"
#include "core/testing/capture_port.h"

namespace {

using hmc::testing::CapturePort;

// Feeds `line` and LF; returns the parser for its token_offset().
hmc::fw::FrameParser parsed(const std::string& line) {
  hmc::fw::FrameParser parser;
  for (const char c : line) parser.feed(static_cast<uint8_t>(c));
  REQUIRE(parser.feed('\n'));
  return parser;
}

}  // namespace

TEST_CASE("ACK and NAK are frames of the command grammar") {
  using hmc::proto::ChecksumMode;
  CapturePort port;
  hmc::fw::write_ack(port, ChecksumMode::kSum);
  hmc::fw::write_nak(port, hmc::proto::Reason::kChecksumMismatch, 8, 24, ChecksumMode::kSum);
  hmc::fw::write_nak(port, hmc::proto::Reason::kLineTooLong, hmc::proto::kNoToken, 128, ChecksumMode::kSum);
  CHECK(port.text == "STX#1#ACK#0#ETX\nSTX#4#NAK#8#8#24#40#ETX\nSTX#4#NAK#1#255#128#128#ETX\n");
}

TEST_CASE("in CRC-16 mode the checksum field is the CRC of the bytes before it") {
  using hmc::proto::ChecksumMode;
  CapturePort port;
  hmc::fw::write_ack(port, ChecksumMode::kCrc16);
  hmc::fw::write_nak(port, hmc::proto::Reason::kChecksumMismatch, 8, 24, ChecksumMode::kCrc16);
  // CRC-16 (0x1021, init 0xFFFF) of "STX#1#ACK#" is 20688, of "STX#4#NAK#8#8#24#" 48728.
  CHECK(port.text == "STX#1#ACK#20688#ETX\nSTX#4#NAK#8#8#24#48728#ETX\n");
}

TEST_CASE("in CRC-16 mode the checksum field is always 5 digits, zero-padded") {
  using hmc::proto::ChecksumMode;
  using hmc::proto::Reason;
  CapturePort port;
  // CRC-16 of "STX#4#NAK#1#0#10#" is 557, of "STX#4#NAK#1#8#10#" 0.
  hmc::fw::write_nak(port, Reason::kLineTooLong, 0, 10, ChecksumMode::kCrc16);
  hmc::fw::write_nak(port, Reason::kLineTooLong, 8, 10, ChecksumMode::kCrc16);
  CHECK(port.text == "STX#4#NAK#1#0#10#00557#ETX\nSTX#4#NAK#1#8#10#00000#ETX\n");
}

TEST_CASE("large values print in full and the sum wraps at 256") {
  CapturePort port;
  const uint32_t values[] = {2, 2147483647u, 0, 128, 50000, 322, 3, 0, 40000};
  static_assert(std::size(values) == std::size(hmc::proto::kVersionFields));
  hmc::fw::write_frame(port, hmc::proto::BoardFrameId::kVersion, values, hmc::proto::ChecksumMode::kSum);
  // 2 + 2147483647 + 128 + 50000 + 322 + 3 + 40000 = 2147574102; mod 256 = 86.
  CHECK(port.text == "STX#10#VER#2#2147483647#0#128#50000#322#3#0#40000#86#ETX\n");
}

TEST_CASE("put_signed splits a position into sign and magnitude") {
  uint32_t out[2];
  hmc::fw::put_signed(out, -1600);
  CHECK(out[0] == 1);
  CHECK(out[1] == 1600);
  hmc::fw::put_signed(out, INT32_MIN);
  CHECK(out[1] == 2147483647u);  // saturated: the grammar's largest number
  hmc::fw::put_signed(out, 7);
  CHECK((out[0] == 0 && out[1] == 7));
}

TEST_CASE("token_offset locates a token of the last line, leading blanks included") {
  const hmc::fw::FrameParser parser = parsed("  STX#6#STM#3#1#8#0#20#32#ETX");
  CHECK(parser.token_offset(0) == 2);
  CHECK(parser.token_offset(2) == 8);   // STM
  CHECK(parser.token_offset(4) == 14);  // dir
  CHECK(parser.token_offset(7) == 20);  // delay_us
  CHECK(parser.token_offset(20) == 29); // past the last token: the line's end
}
