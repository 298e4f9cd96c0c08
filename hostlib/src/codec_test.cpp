// Unit tests of the host codec: decode diagnostics, encode, validate, lint, typed input.
#include "hmc/codec.h"

#include <catch2/catch.hpp>

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
