// Unit tests of the host codec: decode diagnostics, encode, validate, lint, typed input.
#include "hmc/codec.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <string>
#include <vector>

using hmc::decode;
using hmc::proto::Reason;

namespace {

hmc::Diagnostic refusal(std::string_view line) {
  auto r = decode(line);
  REQUIRE_FALSE(r.ok());
  return r.error();
}

}  // namespace

TEST_CASE("decode accepts the spec's first stepper example") {
  auto r = decode("STX#6#STM#1#1#128#1000#500#94#ETX");
  REQUIRE(r.ok());
  CHECK(r->canonical);
  CHECK(r->warnings.empty());
  CHECK(std::get<hmc::StepperMove>(r->command) == hmc::StepperMove{1, 1, 128, 1000, 500});
}

TEST_CASE("the spec's example 5 fails with the checksum it should have") {
  const auto d = refusal("STX#6#STM#3#1#1#11#1000#238#ETX");
  CHECK(d.reason == Reason::kChecksumMismatch);
  CHECK(d.token == 8);
  CHECK(d.offset == 24);
  CHECK(d.expected == 248);
  CHECK(d.found == 238);
  CHECK(d.field == "checksum");
  CHECK(d.message.find("checksum is 238 where 248 was expected") != std::string::npos);
}

TEST_CASE("encode fills in length and checksum") {
  auto frame = hmc::encode(hmc::StepperMove{1, 1, 128, 1000, 500});
  REQUIRE(frame.ok());
  CHECK(*frame == "STX#6#STM#1#1#128#1000#500#94#ETX");
  CHECK(*hmc::encode(hmc::LedColor{1, 200, 120, 100, 20}) == "STX#6#LED#1#200#120#100#20#185#ETX");
  CHECK(*hmc::encode(hmc::ServoMove{2, 90}) == "STX#3#SVM#2#90#92#ETX");
}

TEST_CASE("encode refuses what the board would refuse") {
  auto bad = hmc::encode(hmc::StepperMove{1, 1, 3, 100, 500});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().reason == Reason::kOutOfRange);
  CHECK(bad.error().field == "microstep");
  CHECK(bad.error().token == 5);
  CHECK(bad.error().offset == 14);  // STX#6#STM#1#1#3#...
  auto home3 = hmc::encode(hmc::StepperMove{3, 3, 0, 0, 0});
  REQUIRE_FALSE(home3.ok());
  CHECK(home3.error().reason == Reason::kNoSwitch);
}

TEST_CASE("leading zeros and blanks are accepted but not canonical") {
  auto r = decode("  STX#06#STM#1#1#128#1000#0500#94#ETX\t");
  REQUIRE(r.ok());
  CHECK_FALSE(r->canonical);
  CHECK(*hmc::encode(r->command) == "STX#6#STM#1#1#128#1000#500#94#ETX");
  auto t = decode("STX#6#STM#1#1#128#1000#500#94#ETX\r\n");
  REQUIRE(t.ok());
  CHECK(t->canonical);
}

TEST_CASE("the order of checks decides between coexisting errors") {
  // Bad byte before everything else in the frame.
  CHECK(refusal("stx#6#STM#1#1#128#1000#5\xE9#94#ETX").reason == Reason::kBadByte);
  // Start before end.
  CHECK(refusal("[#STM#1#1#128#1000#500]").reason == Reason::kBadStart);
  // End before length.
  CHECK(refusal("STX#6#STM#1#1#128#1000#500#94#ETX]").reason == Reason::kBadEnd);
  // Checksum before range.
  CHECK(refusal("STX#3#SVM#1#5#7#ETX").reason == Reason::kChecksumMismatch);
  CHECK(refusal("STX#3#SVM#1#5#6#ETX").reason == Reason::kOutOfRange);
  // Range before switch.
  CHECK(refusal("STX#6#STM#3#3#5#0#0#11#ETX").reason == Reason::kOutOfRange);
  CHECK(refusal("STX#6#STM#3#3#0#0#0#6#ETX").reason == Reason::kNoSwitch);
}

TEST_CASE("numbers: digits, limits and signs") {
  CHECK(decode("STX#6#STM#1#1#1#2147483647#500#246#ETX").ok());
  const auto big = refusal("STX#6#STM#1#1#1#2147483648#500#247#ETX");
  CHECK(big.reason == Reason::kBadNumber);
  CHECK(big.field == "steps");
  CHECK(decode("STX#3#SVM#0000000001#10#11#ETX").ok());
  CHECK(refusal("STX#3#SVM#00000000001#10#11#ETX").reason == Reason::kBadNumber);
  CHECK(refusal("STX#3#SVM#+1#10#11#ETX").reason == Reason::kBadNumber);
  CHECK(refusal("STX#3#SVM##10#11#ETX").reason == Reason::kBadNumber);
  const auto space = refusal("STX#3#SVM#1 #10#11#ETX");
  CHECK(space.reason == Reason::kBadByte);
  CHECK(space.field == "servo");
  CHECK(space.offset == 11);
}

TEST_CASE("lengths: frame, command and room") {
  const auto mismatch = refusal("STX#6#SVM#1#10#11#ETX");
  CHECK(mismatch.reason == Reason::kBadLength);
  CHECK(mismatch.expected == 6);
  CHECK(mismatch.found == 3);
  const auto wrong_for_command = refusal("STX#4#SVM#1#10#0#11#ETX");
  CHECK(wrong_for_command.reason == Reason::kBadLength);
  CHECK(wrong_for_command.expected == 3);
  CHECK(wrong_for_command.found == 4);
  CHECK(refusal("STX#ETX").reason == Reason::kBadLength);
  CHECK(refusal("STX").reason == Reason::kBadEnd);
}

TEST_CASE("line length limit is 128 bytes") {
  const std::string frame = "STX#3#SVM#1#10#11#ETX";
  CHECK(decode(std::string(128 - frame.size(), ' ') + frame).ok());
  const auto d = refusal(std::string(129 - frame.size(), ' ') + frame);
  CHECK(d.reason == Reason::kLineTooLong);
  CHECK(d.token == hmc::kNoToken);
  CHECK(d.offset == 128);
}

TEST_CASE("stop is never refused for its other fields; home uses zeros as defaults") {
  CHECK(decode("STX#6#STM#1#0#3#7#9#20#ETX").ok());
  CHECK(decode("STX#6#STM#1#3#0#0#0#4#ETX").ok());
  CHECK(refusal("STX#6#STM#1#1#0#10#500#0#ETX").field == "microstep");
  CHECK(refusal("STX#6#STM#1#1#1#10#0#13#ETX").field == "delay_us");
}

TEST_CASE("lint warns outside the advised delay") {
  auto fast = decode("STX#6#STM#3#1#8#0#20#32#ETX");
  REQUIRE(fast.ok());
  REQUIRE(fast->warnings.size() == 1);
  CHECK(fast->warnings[0].field == "delay_us");
  CHECK(hmc::lint(hmc::StepperMove{1, 1, 1, 1, 3001}).size() == 1);
  CHECK(hmc::lint(hmc::StepperMove{1, 1, 1, 1, 3000}).empty());
  CHECK(hmc::lint(hmc::StepperMove{1, 3, 0, 0, 0}).empty());
  CHECK(hmc::lint(hmc::StepperMove{1, 0, 0, 0, 0}).empty());
}

TEST_CASE("parse_input takes command-set notation and frames") {
  auto n = hmc::parse_input(" [#SVM#1#135] ");
  REQUIRE(n.ok());
  CHECK(std::get<hmc::ServoMove>(*n) == hmc::ServoMove{1, 135});
  CHECK(hmc::parse_input("STX#3#SVM#1#135#136#ETX").ok());
  CHECK(hmc::parse_input("[#SVM#1]").error().reason == Reason::kBadLength);
  CHECK(hmc::parse_input("[#SVM#1#200]").error().reason == Reason::kOutOfRange);
  CHECK(hmc::parse_input("[#SVM#1#135").error().reason == Reason::kBadEnd);
  CHECK(hmc::parse_input("[SVM#1#135]").error().reason == Reason::kBadStart);
  CHECK(hmc::parse_input("[#XYZ#1]").error().reason == Reason::kUnknownCommand);
  CHECK(hmc::parse_input("[#SVM#1#" + std::string(200, '1') + "]").error().reason == Reason::kLineTooLong);
}

TEST_CASE("command_from_words builds and checks a command") {
  auto c = hmc::command_from_words({"stm", "1", "1", "128", "1000", "500"});
  REQUIRE(c.ok());
  CHECK(*hmc::encode(*c) == "STX#6#STM#1#1#128#1000#500#94#ETX");
  auto few = hmc::command_from_words({"SVM", "1"});
  REQUIRE_FALSE(few.ok());
  CHECK(few.error().message.find("SVM <servo> <angle>") != std::string::npos);
  CHECK(hmc::command_from_words({"LED", "1", "2", "3", "4", "x"}).error().field == "w");
}

TEST_CASE("command_from_text takes a frame, notation or words on one line") {
  CHECK(*hmc::encode(*hmc::command_from_text("  SET 1\t7 16 ")) == "STX#4#SET#1#7#16#24#ETX");
  CHECK(*hmc::encode(*hmc::command_from_text("[#SVM#1#135]")) == "STX#3#SVM#1#135#136#ETX");
  CHECK(*hmc::encode(*hmc::command_from_text("STX#3#SVM#1#135#136#ETX")) == "STX#3#SVM#1#135#136#ETX");
  CHECK(hmc::command_from_text("SVM 1").error().reason == hmc::proto::Reason::kBadLength);
  CHECK(hmc::command_from_text("   ").error().reason == hmc::proto::Reason::kUnknownCommand);
}

TEST_CASE("protocol v2 commands encode, decode and describe") {
  CHECK(*hmc::encode(hmc::VersionQuery{}) == "STX#1#VER#0#ETX");
  auto ver = decode("STX#1#VER#0#ETX");
  REQUIRE(ver.ok());
  CHECK(std::holds_alternative<hmc::VersionQuery>(ver->command));
  CHECK(hmc::describe(ver->command) == "ask for the version and capabilities");

  auto set = hmc::command_from_words({"SET", "1", "3", "8000"});
  REQUIRE(set.ok());
  CHECK(std::get<hmc::SetSetting>(*set) == hmc::SetSetting{1, 3, 8000});
  CHECK(*hmc::encode(*set) == "STX#4#SET#1#3#8000#68#ETX");
  CHECK(hmc::describe(*set) == "stepper 1: set accel (steps/s^2; 0 constant rate) to 8000");

  CHECK(*hmc::encode(hmc::StatusQuery{4}) == "STX#2#STA#4#4#ETX");
  CHECK(hmc::describe(hmc::StatusQuery{5}) == "ask for the status of LED strip 1");
  CHECK(*hmc::encode(hmc::GetSetting{2, 8}) == "STX#3#GET#2#8#10#ETX");
  CHECK(*hmc::encode(hmc::SoftLimits{1, 1, 1600, 0, 409600}) == "STX#6#LIM#1#1#1600#0#409600#" +
                                                                    std::to_string((1 + 1 + 1600 + 409600) % 256) +
                                                                    "#ETX");
  CHECK(hmc::describe(hmc::SoftLimits{1, 1, 1600, 0, 409600}) == "stepper 1: soft limits -1600 to 409600 (1/256 step)");
  CHECK(hmc::describe(hmc::SoftLimits{1, 0, 0, 0, 0}) == "stepper 1: no soft limits");
  CHECK(*hmc::encode(hmc::ChecksumModeCommand{1}) == "STX#2#CRC#1#1#ETX");
  CHECK(hmc::parse_input("[#VER]").ok());
  CHECK(std::get<hmc::GetSetting>(*hmc::parse_input(" [#GET#3#1] ")) == hmc::GetSetting{3, 1});
}

TEST_CASE("a setting's value is ranged by the setting it names") {
  // current_ma is 100-4000; accel 0-2000000.
  CHECK(decode("STX#4#SET#1#1#4000#162#ETX").ok());
  const auto high = refusal("STX#4#SET#1#1#4001#163#ETX");
  CHECK(high.reason == Reason::kOutOfRange);
  CHECK(high.token == 5);
  CHECK(high.offset == 14);
  CHECK(high.found == 4001);
  CHECK(high.field == "value");
  CHECK(high.message == "value is 4001: expected 100-4000 for setting 1 (current_ma)");
  CHECK(decode("STX#4#SET#1#3#0#4#ETX").ok());
  // The setting is checked before the value it ranges.
  const auto setting = refusal("STX#4#SET#1#10#0#11#ETX");
  CHECK(setting.token == 4);
  CHECK(setting.field == "setting");
  auto words = hmc::command_from_words({"set", "2", "4", "0"});
  REQUIRE_FALSE(words.ok());
  CHECK(words.error().message == "value is 0: expected 1-50000 for setting 4 (max_rate)");
}

TEST_CASE("lint warns about soft limits that switch themselves off") {
  CHECK(hmc::lint(hmc::SoftLimits{1, 0, 0, 0, 0}).empty());
  CHECK(hmc::lint(hmc::SoftLimits{1, 1, 5, 0, 5}).empty());
  const auto w = hmc::lint(hmc::SoftLimits{1, 0, 10, 1, 10});
  REQUIRE(w.size() == 1);
  CHECK(w[0].message.find("low 10 is not below high -10") != std::string::npos);
}

TEST_CASE("CRC-16 mode: the checksum field is the CRC of the bytes before it") {
  using hmc::proto::ChecksumMode;
  const auto crc = ChecksumMode::kCrc16;
  CHECK(*hmc::encode(hmc::StepperMove{1, 1, 128, 1000, 500}, crc) == "STX#6#STM#1#1#128#1000#500#20499#ETX");
  CHECK(*hmc::encode(hmc::VersionQuery{}, crc) == "STX#1#VER#04369#ETX");  // always 5 digits
  CHECK(hmc::checksum(hmc::SetSetting{1, 3, 8000}, crc) == 26126);
  CHECK(hmc::checksum(hmc::SetSetting{1, 3, 8000}) == 68);

  auto ok = decode("STX#6#STM#1#1#128#1000#500#20499#ETX", crc);
  REQUIRE(ok.ok());
  CHECK(ok->canonical);
  // Blanks around the frame are outside the CRC; leading zeros are inside it.
  CHECK(decode("  STX#6#STM#1#1#128#1000#500#20499#ETX ", crc).ok());
  CHECK(decode("STX#6#STM#1#1#128#1000#0500#20499#ETX", crc).error().reason == Reason::kChecksumMismatch);

  // The seed's sum in CRC mode, and a CRC in sum mode, are named as such.
  auto sum = decode("STX#6#STM#1#1#128#1000#500#00094#ETX", crc);
  REQUIRE_FALSE(sum.ok());
  CHECK(sum.error().reason == Reason::kChecksumMismatch);
  CHECK(sum.error().expected == 20499);
  CHECK(sum.error().found == 94);
  CHECK(sum.error().message.find("this is the seed's sum") != std::string::npos);
  auto short_sum = decode("STX#6#STM#1#1#128#1000#500#94#ETX", crc);
  REQUIRE_FALSE(short_sum.ok());
  CHECK(short_sum.error().reason == Reason::kBadNumber);
  CHECK(short_sum.error().message.find("this is the seed's sum") != std::string::npos);
  auto crc_in_sum = refusal("STX#6#STM#1#1#128#1000#500#20499#ETX");
  CHECK(crc_in_sum.reason == Reason::kOutOfRange);
  CHECK(crc_in_sum.message.find("this is the frame's CRC-16") != std::string::npos);

  auto big = decode("STX#1#VER#65536#ETX", crc);
  REQUIRE_FALSE(big.ok());
  CHECK(big.error().reason == Reason::kOutOfRange);
  CHECK(big.error().found == 65536);
  CHECK(big.error().offset == 10);
  CHECK(hmc::parse_input("STX#1#VER#04369#ETX", crc).ok());
  CHECK_FALSE(hmc::parse_input("STX#1#VER#04369#ETX").ok());
}

TEST_CASE("CRC-16 mode: the checksum field is exactly 5 digits, zero-padded") {
  using hmc::proto::ChecksumMode;
  const auto crc = ChecksumMode::kCrc16;
  auto padded = decode("STX#1#VER#04369#ETX", crc);
  REQUIRE(padded.ok());
  CHECK(padded->canonical);  // the padding is the canonical form
  for (const char* line : {"STX#1#VER#4369#ETX", "STX#1#VER#004369#ETX"}) {
    INFO(line);
    auto d = decode(line, crc);
    REQUIRE_FALSE(d.ok());
    CHECK(d.error().reason == Reason::kBadNumber);
    CHECK(d.error().token == 3);
    CHECK(d.error().offset == 10);
    CHECK(d.error().field == "checksum");
    CHECK(d.error().message.find("in CRC-16 mode the checksum is exactly 5 digits") != std::string::npos);
    CHECK(d.error().message.find("'04369'") != std::string::npos);
  }
  // A digit moved across the '#' into the checksum field (the corruption soak's find).
  CHECK(decode("STX#6#STM#1#1#128#1000#50#020499#ETX", crc).error().reason == Reason::kBadNumber);
  // The seed's sum keeps any width.
  CHECK(decode("STX#1#VER#00#ETX").ok());
}

TEST_CASE("unknown names list the commands and point at the other direction") {
  const auto d = refusal("STX#1#ACK#0#ETX");
  CHECK(d.reason == Reason::kUnknownCommand);
  CHECK(d.message.find("STM, SVM, LED, VER, STA, SET, GET, LIM, CRC, WDG and POS") != std::string::npos);
  CHECK(d.message.find("ACK is one of the board frames") != std::string::npos);
}

TEST_CASE("every number is written and read back digit for digit, whatever its length") {
  // Values at every digit count and group boundary, and zeros inside groups ("1000005").
  std::vector<uint32_t> values = {0, 1, 9, 10, 99, 100, 999, 1000, 1001, 9999, 10000, 100000, 999999, 1000000,
                                  1000005, 12345678, 99999999, 100000000, 999999999, 1000000000, 2000000999,
                                  2147483647};
  for (uint32_t v = 1; v < 2147483647u / 7; v = v * 7 + 3) values.push_back(v);
  for (const uint32_t steps : values) {
    INFO("steps " << steps);
    const hmc::StepperMove move{2, 1, 16, steps, 700};
    const std::string expected = "STX#6#STM#2#1#16#" + std::to_string(steps) + "#700#" +
                                 std::to_string((2 + 1 + 16 + steps + 700) % 256) + "#ETX";
    const auto frame = hmc::encode(move);
    REQUIRE(frame.ok());
    CHECK(*frame == expected);
    const auto back = decode(*frame);
    REQUIRE(back.ok());
    CHECK(back->canonical);
    CHECK(std::get<hmc::StepperMove>(back->command) == move);
  }
}

TEST_CASE("CRC-16 checksum fields are five digits for CRCs of every width") {
  using hmc::proto::ChecksumMode;
  std::array<int, 5> seen{};  // CRCs of 1, 2, 3, 4 and 5 digits
  for (uint32_t k = 0; k < 300000 && std::count(seen.begin(), seen.end(), 0) > 0; ++k) {
    const hmc::LedColor colour{1 + k % 2, k % 256, (k / 256) % 256, (k / 65536) % 256, 7};
    const uint32_t crc = hmc::checksum(colour, ChecksumMode::kCrc16);
    const std::string digits = std::to_string(crc);
    ++seen[digits.size() - 1];
    const auto frame = hmc::encode(colour, ChecksumMode::kCrc16);
    REQUIRE(frame.ok());
    const std::string field = frame->substr(frame->size() - 9, 6);  // "ddddd#" before "ETX"
    REQUIRE(field == std::string(5 - digits.size(), '0') + digits + "#");
    REQUIRE(decode(*frame, ChecksumMode::kCrc16).ok());
  }
  CHECK(std::count(seen.begin(), seen.end(), 0) == 0);
}

TEST_CASE("encode_into writes the frame encode() returns, and no frame for a refused command") {
  hmc::FrameText text;
  const hmc::StepperMove move{1, 1, 128, 1000, 500};
  auto written = hmc::encode_into(move, text);
  REQUIRE(written.ok());
  CHECK(*written == text.size);
  CHECK(text.view() == *hmc::encode(move));
  auto refused = hmc::encode_into(hmc::StepperMove{1, 1, 3, 100, 500}, text);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().field == "microstep");
  CHECK(text.size == 0);
  // Home, stop and setting values are judged by the rules, not the fields' own ranges alone.
  CHECK(hmc::encode_into(hmc::StepperMove{1, 3, 0, 0, 0}, text).ok());
  CHECK(text.view() == "STX#6#STM#1#3#0#0#0#4#ETX");
  CHECK(hmc::encode_into(hmc::StepperMove{3, 0, 0, 0, 0}, text).ok());
  CHECK_FALSE(hmc::encode_into(hmc::StepperMove{3, 3, 0, 0, 0}, text).ok());
  CHECK_FALSE(hmc::encode_into(hmc::SetSetting{1, hmc::proto::kSettingCurrent, 100000}, text).ok());
}

TEST_CASE("LED colours as people write them") {
  CHECK(hmc::parse_led_colour(2, "#ff800010").value() == hmc::LedColor{2, 255, 128, 0, 16});
  CHECK(hmc::parse_led_colour(1, "00ff00").value() == hmc::LedColor{1, 0, 255, 0, 0});
  CHECK(hmc::parse_led_colour(1, "off").value() == hmc::LedColor{1, 0, 0, 0, 0});
  CHECK_FALSE(hmc::parse_led_colour(1, "#12"));
  CHECK_FALSE(hmc::parse_led_colour(1, "#gg0000"));
}
