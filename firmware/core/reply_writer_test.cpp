// Tests of the reply frames and of FrameParser::token_offset, which locates a rule refusal's
// token in the line the parser accepted.
#include "core/reply_writer.h"

#include <catch2/catch.hpp>

#include <string>

#include "core/frame_parser.h"

namespace {

class CapturePort : public hmc::hal::SerialPort {
 public:
  int read_byte() override { return -1; }
  void write(const uint8_t* bytes, uint32_t count) override {
    text.append(reinterpret_cast<const char*>(bytes), count);
  }
  std::string text;
};

// Feeds `line` and LF; returns the parser for its token_offset().
hmc::fw::FrameParser parsed(const std::string& line) {
  hmc::fw::FrameParser parser;
  for (const char c : line) parser.feed(static_cast<uint8_t>(c));
  REQUIRE(parser.feed('\n'));
  return parser;
}

}  // namespace

TEST_CASE("ACK and NAK are frames of the command grammar") {
  CapturePort port;
  hmc::fw::write_ack(port);
  hmc::fw::write_nak(port, hmc::proto::Reason::kChecksumMismatch, 8, 24);
  hmc::fw::write_nak(port, hmc::proto::Reason::kLineTooLong, hmc::proto::kNoToken, 128);
  CHECK(port.text == "STX#1#ACK#0#ETX\nSTX#4#NAK#8#8#24#40#ETX\nSTX#4#NAK#1#255#128#128#ETX\n");
}

TEST_CASE("a reply's checksum is the sum of its values mod 256, and large values print in full") {
  CapturePort port;
  const uint32_t values[] = {4294967295u, 0, 10};
  hmc::fw::write_frame(port, "TST", values, 3);
  CHECK(port.text == "STX#4#TST#4294967295#0#10#9#ETX\n");
}

TEST_CASE("token_offset locates a token of the last line, leading blanks included") {
  const hmc::fw::FrameParser parser = parsed("  STX#6#STM#3#1#8#0#20#32#ETX");
  CHECK(parser.token_offset(0) == 2);
  CHECK(parser.token_offset(2) == 8);   // STM
  CHECK(parser.token_offset(4) == 14);  // dir
  CHECK(parser.token_offset(7) == 20);  // delay_us
  CHECK(parser.token_offset(20) == 29); // past the last token: the line's end
}
