// Unit tests of FrameParser against docs/protocol.md: the spec's examples, every refusal reason,
// the order of checks where two faults meet, line ends, blanks, the line limit and numbers.
// Lines go through feed() byte by byte, as the UART delivers them.
#include "core/frame_parser.h"

#include <catch2/catch.hpp>

#include <stdint.h>

#include <string>
#include <vector>

using hmc::fw::FrameParser;
using hmc::fw::Verdict;
using hmc::proto::CommandId;
using hmc::proto::Reason;

namespace Catch {
// Shows reasons by their protocol names in failure messages.
template <>
struct StringMaker<Reason> {
  static std::string convert(Reason reason) { return hmc::proto::reason_spec(reason).name; }
};
}  // namespace Catch

namespace {

// Feeds bytes to a parser; returns the verdicts they completed, in order.
std::vector<Verdict> feed_bytes(FrameParser& parser, const std::string& bytes) {
  std::vector<Verdict> verdicts;
  for (const char c : bytes) {
    if (parser.feed(static_cast<uint8_t>(c))) verdicts.push_back(parser.verdict());
  }
  return verdicts;
}

// The verdict of one line fed to a fresh parser and ended by LF, which must give exactly one.
Verdict judge(const std::string& line) {
  FrameParser parser;
  const std::vector<Verdict> verdicts = feed_bytes(parser, line + "\n");
  REQUIRE(verdicts.size() == 1);
  return verdicts[0];
}

// Checks a verdict is this exact refusal.
void check_refusal(const Verdict& verdict, Reason reason, unsigned token, unsigned offset,
                   uint32_t expected, uint32_t found) {
  CHECK(verdict.reason == reason);
  CHECK(unsigned{verdict.token} == token);
  CHECK(unsigned{verdict.offset} == offset);
  CHECK(verdict.expected == expected);
  CHECK(verdict.found == found);
}

// Checks a line is refused with exactly this reason, token, offset, expected and found.
void require_refused(const std::string& line, Reason reason, unsigned token, unsigned offset,
                     uint32_t expected = 0, uint32_t found = 0) {
  INFO("line: " << line);
  check_refusal(judge(line), reason, token, offset, expected, found);
}

// Checks a line is accepted as this stepper command, with nothing else in the verdict.
void require_stepper(const std::string& line, unsigned motor, unsigned dir, uint32_t microstep,
                     uint32_t steps, uint32_t delay_us) {
  INFO("line: " << line);
  const Verdict verdict = judge(line);
  REQUIRE(verdict.reason == Reason::kOk);
  CHECK(unsigned{verdict.token} == 0);
  CHECK(unsigned{verdict.offset} == 0);
  CHECK(verdict.expected == 0);
  CHECK(verdict.found == 0);
  REQUIRE(verdict.command.id == CommandId::kStepper);
  CHECK(unsigned{verdict.command.stepper.motor} == motor);
  CHECK(unsigned{verdict.command.stepper.dir} == dir);
  CHECK(verdict.command.stepper.microstep == microstep);
  CHECK(verdict.command.stepper.steps == steps);
  CHECK(verdict.command.stepper.delay_us == delay_us);
}

// Checks a line is accepted as this servo command.
void require_servo(const std::string& line, unsigned servo, unsigned angle) {
  INFO("line: " << line);
  const Verdict verdict = judge(line);
  REQUIRE(verdict.reason == Reason::kOk);
  REQUIRE(verdict.command.id == CommandId::kServo);
  CHECK(unsigned{verdict.command.servo.servo} == servo);
  CHECK(unsigned{verdict.command.servo.angle} == angle);
}

const std::string kServoFrame = "STX#3#SVM#1#90#91#ETX";  // 21 bytes, accepted

}  // namespace

TEST_CASE("the spec's examples get the spec's verdicts", "[frame_parser]") {
  require_stepper("STX#6#STM#1#1#128#1000#500#94#ETX", 1, 1, 128, 1000, 500);
  require_refused("STX#6#STM#3#1#1#11#1000#238#ETX", Reason::kChecksumMismatch, 8, 24, 248, 238);
  require_refused("[#STM#1#1#128#1000#500]", Reason::kBadStart, 0, 0);
  require_refused("STX#6#STM#3#3#0#0#0#6#ETX", Reason::kNoSwitch, 3, 10);
  require_refused("STX#3#SVM#1#5#6#ETX", Reason::kOutOfRange, 4, 12, 0, 5);
  require_stepper("STX#6#STM#1#0#3#7#9#20#ETX", 1, 0, 3, 7, 9);
  require_stepper("STX#6#STM#1#0#0#0#0#1#ETX", 1, 0, 0, 0, 0);  // the seed's stop frame
}

TEST_CASE("servo and LED frames are accepted with their fields", "[frame_parser]") {
  require_servo(kServoFrame, 1, 90);
  require_servo("STX#3#SVM#2#170#172#ETX", 2, 170);
  require_servo("STX#3#SVM#1#10#11#ETX", 1, 10);

  const Verdict led = judge("STX#6#LED#2#255#0#128#7#136#ETX");
  REQUIRE(led.reason == Reason::kOk);
  REQUIRE(led.command.id == CommandId::kLed);
  CHECK(unsigned{led.command.led.strip} == 2);
  CHECK(unsigned{led.command.led.r} == 255);
  CHECK(unsigned{led.command.led.g} == 0);
  CHECK(unsigned{led.command.led.b} == 128);
  CHECK(unsigned{led.command.led.w} == 7);
}

TEST_CASE("every reason is reported with its token and offset", "[frame_parser]") {
  SECTION("line_too_long") {
    check_refusal(judge(std::string(129, 'A')), Reason::kLineTooLong, hmc::proto::kNoToken, 128, 0,
                  0);
  }
  SECTION("bad_byte") {
    require_refused("STX#3#SVM#1#\t90#91#ETX", Reason::kBadByte, 4, 12);
    require_refused("STX#3#SVM#1#9 0#91#ETX", Reason::kBadByte, 4, 13);
    require_refused(std::string("\0STX#3#SVM#1#90#91#ETX", 22), Reason::kBadByte, 0, 0);
    require_refused("STX#3#SVM#1#90#91#ETX\x7f", Reason::kBadByte, 6, 21);
  }
  SECTION("bad_start") {
    require_refused("STx#3#SVM#1#90#91#ETX", Reason::kBadStart, 0, 0);
    require_refused("#STX#3#SVM#1#90#91#ETX", Reason::kBadStart, 0, 0);
    require_refused("STXSTX#3#SVM#1#90#91#ETX", Reason::kBadStart, 0, 0);
  }
  SECTION("bad_end") {
    require_refused("STX#3#SVM#1#90#91#etx", Reason::kBadEnd, 6, 18);
    require_refused("STX#3#SVM#1#90#91#ETX#", Reason::kBadEnd, 7, 22);  // empty last token
    require_refused("STX#3#SVM#1#90#91", Reason::kBadEnd, 5, 15);
    require_refused("STX", Reason::kBadEnd, 0, 0);
  }
  SECTION("bad_length: too few tokens") {
    require_refused("STX#ETX", Reason::kBadLength, 1, 4);
    require_refused("STX#1#ETX", Reason::kBadLength, 1, 4);
    require_refused("STX#1#SVM#ETX", Reason::kBadLength, 1, 4);
  }
  SECTION("bad_length: the length disagrees with the frame") {
    require_refused("STX#3#SVM#1#90#ETX", Reason::kBadLength, 1, 4, 3, 2);
    require_refused("STX#2#SVM#1#90#91#ETX", Reason::kBadLength, 1, 4, 2, 3);
  }
  SECTION("bad_length: the length disagrees with the command") {
    require_refused("STX#3#STM#1#1#2#ETX", Reason::kBadLength, 1, 4, 6, 3);
    require_refused("STX#6#SVM#1#90#0#0#0#91#ETX", Reason::kBadLength, 1, 4, 3, 6);
  }
  SECTION("bad_number") {
    require_refused("STX#x#SVM#1#90#91#ETX", Reason::kBadNumber, 1, 4);
    require_refused("STX##SVM#1#90#91#ETX", Reason::kBadNumber, 1, 4);
    require_refused("STX#3#SVM#1#9a#91#ETX", Reason::kBadNumber, 4, 12);
    require_refused("STX#3#SVM##90#91#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#3#SVM#+1#90#91#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#3#SVM#-1#90#91#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#3#SVM#1.0#90#91#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#3#SVM#1#90#x#ETX", Reason::kBadNumber, 5, 15);
    require_refused("STX#3#SVM#1#90##ETX", Reason::kBadNumber, 5, 15);
  }
  SECTION("unknown_command") {
    require_refused("STX#3#SVX#1#90#91#ETX", Reason::kUnknownCommand, 2, 6);
    require_refused("STX#3#svm#1#90#91#ETX", Reason::kUnknownCommand, 2, 6);
    require_refused("STX#3#SV#1#90#91#ETX", Reason::kUnknownCommand, 2, 6);
    require_refused("STX#3#SVMM#1#90#91#ETX", Reason::kUnknownCommand, 2, 6);
    require_refused("STX#3##1#90#91#ETX", Reason::kUnknownCommand, 2, 6);
  }
  SECTION("checksum_mismatch") {
    require_refused("STX#3#SVM#1#90#90#ETX", Reason::kChecksumMismatch, 5, 15, 91, 90);
  }
  SECTION("out_of_range") {
    require_refused("STX#3#SVM#1#90#256#ETX", Reason::kOutOfRange, 5, 15, 0, 256);  // checksum
    require_refused("STX#3#SVM#3#90#93#ETX", Reason::kOutOfRange, 3, 10, 0, 3);
    require_refused("STX#3#SVM#1#171#172#ETX", Reason::kOutOfRange, 4, 12, 0, 171);
    require_refused("STX#6#LED#1#256#0#0#0#1#ETX", Reason::kOutOfRange, 4, 12, 0, 256);
    require_refused("STX#6#LED#0#0#0#0#0#0#ETX", Reason::kOutOfRange, 3, 10, 0, 0);
    require_refused("STX#6#STM#1#4#3#0#0#8#ETX", Reason::kOutOfRange, 4, 12, 0, 4);
  }
  SECTION("no_switch") {
    require_refused("STX#6#STM#3#3#16#500#800#42#ETX", Reason::kNoSwitch, 3, 10);
  }
}

TEST_CASE("when two checks fail, the earlier one in the order is reported", "[frame_parser]") {
  SECTION("1 length before 2 blank and 3 bytes") {
    require_refused(std::string(129, ' '), Reason::kLineTooLong, hmc::proto::kNoToken, 128);
    require_refused(std::string(129, '\x01'), Reason::kLineTooLong, hmc::proto::kNoToken, 128);
  }
  SECTION("3 bytes before 5 start") {
    require_refused("S X#3#SVM#1#90#91#ETX", Reason::kBadByte, 0, 1);
  }
  SECTION("the first bad byte wins") {
    require_refused("STX#3#SVM#\x01#90#\x02#ETX", Reason::kBadByte, 3, 10);
  }
  SECTION("5 start before 6 end") {
    require_refused("XTX#3#SVM#1#90#91#XTX", Reason::kBadStart, 0, 0);
  }
  SECTION("6 end before 7 room") { require_refused("STX#1#XTX", Reason::kBadEnd, 2, 6); }
  SECTION("7 room before 8 length number") {
    require_refused("STX#x#ETX", Reason::kBadLength, 1, 4);
  }
  SECTION("8 length number before 9 length agreeing with the frame") {
    require_refused("STX#x#SVM#1#ETX", Reason::kBadNumber, 1, 4);
  }
  SECTION("9 length agreeing with the frame before 10 name") {
    require_refused("STX#5#FOO#1#1#ETX", Reason::kBadLength, 1, 4, 5, 2);
  }
  SECTION("10 name before 11 length agreeing with the command") {
    require_refused("STX#4#FOO#1#2#3#6#ETX", Reason::kUnknownCommand, 2, 6);
  }
  SECTION("11 length agreeing with the command before 12 value numbers") {
    require_refused("STX#4#SVM#1#x#3#6#ETX", Reason::kBadLength, 1, 4, 3, 4);
  }
  SECTION("12 value numbers before 13 checksum number, first bad value first") {
    require_refused("STX#3#SVM#a#b#c#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#3#SVM#1#b#c#ETX", Reason::kBadNumber, 4, 12);
  }
  SECTION("13 checksum number before 14 checksum and 15 ranges") {
    require_refused("STX#3#SVM#9#999#z#ETX", Reason::kBadNumber, 5, 16);
    require_refused("STX#3#SVM#9#999#300#ETX", Reason::kOutOfRange, 5, 16, 0, 300);
  }
  SECTION("14 checksum before 15 ranges") {
    require_refused("STX#3#SVM#9#999#0#ETX", Reason::kChecksumMismatch, 5, 16, 240, 0);
  }
  SECTION("15 ranges left to right") {
    require_refused("STX#3#SVM#9#999#240#ETX", Reason::kOutOfRange, 3, 10, 0, 9);
  }
  SECTION("15 the action's own range before the fields that depend on it") {
    require_refused("STX#6#STM#1#4#3#0#0#8#ETX", Reason::kOutOfRange, 4, 12, 0, 4);
  }
  SECTION("15 ranges before 16 switch") {
    require_refused("STX#6#STM#3#3#3#0#0#9#ETX", Reason::kOutOfRange, 5, 14, 0, 3);
  }
}

TEST_CASE("LF, CRLF and a lone CR each end a line once", "[frame_parser]") {
  SECTION("two frames in a row, each with the same line end") {
    struct LineEnd {
      const char* name;
      const char* bytes;
    };
    for (const LineEnd end : {LineEnd{"LF", "\n"}, LineEnd{"CRLF", "\r\n"}, LineEnd{"CR", "\r"},
                              LineEnd{"LFCR", "\n\r"}}) {
      INFO("line end: " << end.name);
      FrameParser parser;
      const std::vector<Verdict> verdicts =
          feed_bytes(parser, kServoFrame + end.bytes + "STX#3#SVM#2#170#172#ETX" + end.bytes);
      REQUIRE(verdicts.size() == 2);
      CHECK(unsigned{verdicts[0].command.servo.servo} == 1);
      CHECK(unsigned{verdicts[1].command.servo.servo} == 2);
    }
  }

  SECTION("only the byte ending a line returns true") {
    FrameParser parser;
    for (const char c : kServoFrame) CHECK_FALSE(parser.feed(static_cast<uint8_t>(c)));
    CHECK(parser.feed('\r'));
    CHECK(parser.verdict().reason == Reason::kOk);
    CHECK_FALSE(parser.feed('\n'));
  }
}

TEST_CASE("blank lines give no verdict", "[frame_parser]") {
  FrameParser parser;
  CHECK(feed_bytes(parser, "\n\r\n\r\r   \n\t\n \t \t\r\n").empty());
  CHECK(feed_bytes(parser, std::string(128, ' ') + "\n").empty());

  Verdict untouched{};
  CHECK_FALSE(FrameParser::parse_line(nullptr, 0, untouched));
  const uint8_t blanks[] = {' ', '\t', ' '};
  CHECK_FALSE(FrameParser::parse_line(blanks, sizeof blanks, untouched));
}

TEST_CASE("blanks around a frame are ignored but count in offsets", "[frame_parser]") {
  require_servo(" \t " + kServoFrame + "\t  ", 1, 90);
  require_refused("  \tSTX#3#SVM#1#5#6#ETX \t", Reason::kOutOfRange, 4, 15, 0, 5);
  require_refused("   XTX#3#SVM#1#90#91#ETX", Reason::kBadStart, 0, 3);
}

TEST_CASE("the line limit is 128 bytes, and the parser resynchronises after it", "[frame_parser]") {
  SECTION("128 bytes is not too long") {
    require_servo(kServoFrame + std::string(128 - kServoFrame.size(), ' '), 1, 90);
    require_servo(std::string(128 - kServoFrame.size(), '\t') + kServoFrame, 1, 90);
    // A 128-byte frame whose last token is empty: its offset is one past the last byte.
    require_refused("STX" + std::string(125, '#'), Reason::kBadEnd, 125, 128);
  }
  SECTION("129 bytes is too long, then the next line is judged afresh") {
    FrameParser parser;
    const std::string long_line = kServoFrame + std::string(129 - kServoFrame.size(), ' ');
    const std::vector<Verdict> verdicts = feed_bytes(parser, long_line + "\n" + kServoFrame + "\n");
    REQUIRE(verdicts.size() == 2);
    check_refusal(verdicts[0], Reason::kLineTooLong, hmc::proto::kNoToken, 128, 0, 0);
    CHECK(verdicts[1].reason == Reason::kOk);
    CHECK(unsigned{verdicts[1].command.servo.angle} == 90);
  }
  SECTION("parse_line takes any length") {
    const std::vector<uint8_t> bytes(1000, 'A');
    Verdict verdict{};
    REQUIRE(FrameParser::parse_line(bytes.data(), 129, verdict));
    check_refusal(verdict, Reason::kLineTooLong, hmc::proto::kNoToken, 128, 0, 0);
    REQUIRE(FrameParser::parse_line(bytes.data(), 1000, verdict));
    CHECK(verdict.reason == Reason::kLineTooLong);
    REQUIRE(FrameParser::parse_line(bytes.data(), 128, verdict));
    CHECK(verdict.reason == Reason::kBadStart);
  }
  SECTION("a refused line does not spoil the next one") {
    FrameParser parser;
    const std::vector<Verdict> verdicts =
        feed_bytes(parser, "STX#3#SVM#1#90#9\xE9#ETX\n" + kServoFrame + "\n");
    REQUIRE(verdicts.size() == 2);
    CHECK(verdicts[0].reason == Reason::kBadByte);
    CHECK(verdicts[1].reason == Reason::kOk);
  }
}

TEST_CASE("thousands of bytes without a line end keep the parser bounded", "[frame_parser]") {
  STATIC_REQUIRE(sizeof(FrameParser) <= hmc::proto::kLineMax + 64);
  FrameParser parser;
  std::string garbage;
  for (uint32_t i = 0; i < 100000; ++i) {
    const auto byte = static_cast<char>((i * 37u + 11u) & 0xFFu);
    garbage += (byte == '\r' || byte == '\n') ? '#' : byte;
  }
  CHECK(feed_bytes(parser, garbage).empty());
  const std::vector<Verdict> verdicts = feed_bytes(parser, "\n" + kServoFrame + "\r\n");
  REQUIRE(verdicts.size() == 2);
  check_refusal(verdicts[0], Reason::kLineTooLong, hmc::proto::kNoToken, 128, 0, 0);
  CHECK(verdicts[1].reason == Reason::kOk);
}

TEST_CASE("numbers are 1 to 10 digits up to INT_MAX, leading zeros allowed", "[frame_parser]") {
  SECTION("ten digits with leading zeros") {
    require_stepper(
        "STX#0000000006#STM#0000000001#0000000001#0000000128#0000001000#0000000500#0000000094#ETX",
        1, 1, 128, 1000, 500);
    require_servo("STX#003#SVM#01#0090#00091#ETX", 1, 90);
  }
  SECTION("INT_MAX is accepted") {
    require_stepper("STX#6#STM#1#1#1#2147483647#2147483647#1#ETX", 1, 1, 1, 2147483647u,
                    2147483647u);
  }
  SECTION("INT_MAX + 1 and wider values are refused") {
    require_refused("STX#6#STM#1#1#1#2147483648#500#246#ETX", Reason::kBadNumber, 6, 16);
    require_refused("STX#6#STM#1#1#1#4294967296#500#246#ETX", Reason::kBadNumber, 6, 16);
    require_refused("STX#6#STM#1#1#1#9999999999#500#246#ETX", Reason::kBadNumber, 6, 16);
  }
  SECTION("eleven digits are refused, even as a small value") {
    require_refused("STX#3#SVM#00000000001#90#91#ETX", Reason::kBadNumber, 3, 10);
    require_refused("STX#00000000003#SVM#1#90#91#ETX", Reason::kBadNumber, 1, 4);
  }
  SECTION("a checksum that is a number above 255 is out of range") {
    require_refused("STX#3#SVM#1#90#2147483647#ETX", Reason::kOutOfRange, 5, 15, 0, 2147483647u);
  }
}

TEST_CASE("stepper ranges follow the action", "[frame_parser]") {
  SECTION("stop leaves microstep, steps and delay unchecked") {
    require_stepper("STX#6#STM#2#0#2147483647#0#0#1#ETX", 2, 0, 2147483647u, 0, 0);
    require_refused("STX#6#STM#4#0#0#0#0#4#ETX", Reason::kOutOfRange, 3, 10, 0, 4);
  }
  SECTION("home accepts microstep 0 and delay 0 on motors with switches") {
    require_stepper("STX#6#STM#1#3#0#0#0#4#ETX", 1, 3, 0, 0, 0);
    require_stepper("STX#6#STM#2#3#16#5000#500#145#ETX", 2, 3, 16, 5000, 500);
    require_refused("STX#6#STM#3#3#0#0#0#6#ETX", Reason::kNoSwitch, 3, 10);
    require_refused("STX#6#STM#1#3#3#0#0#7#ETX", Reason::kOutOfRange, 5, 14, 0, 3);
  }
  SECTION("move wants a power-of-two microstep from 1 to 256 and a delay of at least 1") {
    for (uint32_t microstep = 1; microstep <= 256; microstep *= 2) {
      const uint32_t checksum = (1 + 1 + microstep + 1000 + 500) & 0xFFu;
      require_stepper("STX#6#STM#1#1#" + std::to_string(microstep) + "#1000#500#" +
                          std::to_string(checksum) + "#ETX",
                      1, 1, microstep, 1000, 500);
    }
    require_refused("STX#6#STM#1#1#3#1000#500#225#ETX", Reason::kOutOfRange, 5, 14, 0, 3);
    require_refused("STX#6#STM#1#1#0#1000#500#222#ETX", Reason::kOutOfRange, 5, 14, 0, 0);
    require_refused("STX#6#STM#1#1#512#1000#500#222#ETX", Reason::kOutOfRange, 5, 14, 0, 512);
    require_refused("STX#6#STM#1#1#128#1000#0#106#ETX", Reason::kOutOfRange, 7, 23, 0, 0);
    require_stepper("STX#6#STM#1#2#1#0#1#5#ETX", 1, 2, 1, 0, 1);  // steps 0: run until stopped
  }
}

TEST_CASE("a byte outside printable ASCII is a bad_byte at its offset", "[frame_parser]") {
  require_refused("STX#6#STM#1#1#12\xE9#1000#500#94#ETX", Reason::kBadByte, 5, 16);
  require_refused("  STX#6#STM#1#1#128#1000#500#94#ET\xE9", Reason::kBadByte, 9, 34);
  require_refused("\xE9STX#3#SVM#1#90#91#ETX", Reason::kBadByte, 0, 0);
}

TEST_CASE("random bytes always give verdicts within the protocol's bounds", "[frame_parser]") {
  FrameParser parser;
  uint32_t state = 12345;
  uint32_t verdicts = 0;
  for (uint32_t i = 0; i < 200000; ++i) {
    state = state * 1664525u + 1013904223u;  // a fixed sequence, so a failure repeats
    const uint32_t roll = state >> 24;
    // Mostly frame bytes, with line ends often enough to give lines of every length.
    const uint8_t byte = roll < 4    ? static_cast<uint8_t>('\n')
                         : roll < 64 ? static_cast<uint8_t>("STX#ETXSVMLED0123456789 "[roll % 24])
                                     : static_cast<uint8_t>(state >> 16);
    if (!parser.feed(byte)) continue;
    ++verdicts;
    const Verdict& verdict = parser.verdict();
    REQUIRE(static_cast<uint32_t>(verdict.reason) < hmc::proto::kReasonCount);
    REQUIRE(unsigned{verdict.offset} <= hmc::proto::kLineMax);
    if (verdict.reason == Reason::kOk) REQUIRE(unsigned{verdict.token} == 0);
  }
  CHECK(verdicts > 100);
  const std::vector<Verdict> last = feed_bytes(parser, "\n" + kServoFrame + "\n");
  REQUIRE_FALSE(last.empty());
  CHECK(last.back().reason == Reason::kOk);
}

TEST_CASE("in CRC-16 mode the checksum field is exactly 5 digits, zero-padded", "[frame_parser]") {
  using hmc::proto::ChecksumMode;
  // CRC-16 of "STX#3#SVM#1#90#" is 7353, of "STX#3#SVM#2#20#" 666.
  auto crc_verdict = [](const std::string& line) {
    INFO("line: " << line);
    Verdict verdict{};
    REQUIRE(FrameParser::parse_line(reinterpret_cast<const uint8_t*>(line.data()),
                                    static_cast<uint32_t>(line.size()), verdict, ChecksumMode::kCrc16));
    return verdict;
  };
  CHECK(crc_verdict("STX#3#SVM#1#90#07353#ETX").reason == Reason::kOk);
  const Verdict padded = crc_verdict("STX#3#SVM#2#20#00666#ETX");
  REQUIRE(padded.reason == Reason::kOk);
  CHECK(unsigned{padded.command.servo.angle} == 20);
  // Any other width is a bad_number at the checksum token, even when its value is the CRC.
  check_refusal(crc_verdict("STX#3#SVM#1#90#7353#ETX"), Reason::kBadNumber, 5, 15, 0, 0);
  check_refusal(crc_verdict("STX#3#SVM#1#90#007353#ETX"), Reason::kBadNumber, 5, 15, 0, 0);
  check_refusal(crc_verdict("STX#3#SVM#2#20#666#ETX"), Reason::kBadNumber, 5, 15, 0, 0);
  // A digit moved across the '#' into the checksum field no longer passes.
  check_refusal(crc_verdict("STX#3#SVM#1#9#007353#ETX"), Reason::kBadNumber, 5, 14, 0, 0);
  // Five digits above 65535 are still out_of_range; a wrong CRC is still a mismatch.
  check_refusal(crc_verdict("STX#3#SVM#1#90#99999#ETX"), Reason::kOutOfRange, 5, 15, 0, 99999);
  check_refusal(crc_verdict("STX#3#SVM#1#90#07354#ETX"), Reason::kChecksumMismatch, 5, 15, 7353, 7354);
  // The seed's sum keeps any width of 1-10 digits.
  require_servo("STX#3#SVM#1#90#0091#ETX", 1, 90);
}
