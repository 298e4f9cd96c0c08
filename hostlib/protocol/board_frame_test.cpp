// Unit tests of the board -> host frames: decode_board_frame's verdicts and diagnostics, the
// typed values, encode_board_frame, is_event and the descriptions in words.
#include "hmc/board_frame.h"

#include <catch2/catch.hpp>

#include "hmc/command_json.h"

using hmc::decode_board_frame;
using hmc::proto::ChecksumMode;
using hmc::proto::Reason;

namespace {

hmc::Diagnostic refusal(std::string_view line, ChecksumMode mode = ChecksumMode::kSum) {
  auto r = decode_board_frame(line, mode);
  REQUIRE_FALSE(r.ok());
  return r.error();
}

}  // namespace

TEST_CASE("replies: ACK and NAK") {
  auto ack = decode_board_frame("STX#1#ACK#0#ETX\n");
  REQUIRE(ack.ok());
  CHECK(std::holds_alternative<hmc::Ack>(*ack));
  CHECK_FALSE(hmc::is_event(*ack));
  CHECK(hmc::describe(*ack) == "accepted");
  CHECK(decode_board_frame("STX#1#ACK#20688#ETX", ChecksumMode::kCrc16).ok());

  auto nak = decode_board_frame("STX#4#NAK#8#8#24#40#ETX");
  REQUIRE(nak.ok());
  CHECK(std::get<hmc::Nak>(*nak) == hmc::Nak{Reason::kChecksumMismatch, 8, 24});
  CHECK(hmc::describe(*nak) == "refused: checksum_mismatch at token 8, byte 24");
  auto too_long = decode_board_frame("STX#4#NAK#1#255#128#128#ETX");
  REQUIRE(too_long.ok());
  CHECK(hmc::describe(*too_long) == "refused: line_too_long byte 128");
  CHECK(hmc::board_frame_to_json(*too_long)["token"].is_null());
  // A reason this host does not know yet is still a reply.
  auto newer = decode_board_frame("STX#4#NAK#200#7#20#227#ETX");
  REQUIRE(newer.ok());
  CHECK(hmc::describe(*newer) == "refused: reason 200 at token 7, byte 20");
}

TEST_CASE("STA carries a signed position and packed flags") {
  // motor 1 moving, at -1600 toward 0, 1000 steps/s, flags: homed, end 0 pressed, log2 4 (1/16).
  const uint32_t flags = 1 | 2 | (4 << 4);
  const std::string line = "STX#9#STA#1#1#1#1600#0#0#1000#" + std::to_string(flags) + "#" +
                           std::to_string((1 + 1 + 1 + 1600 + 1000 + flags) % 256) + "#ETX";
  auto r = decode_board_frame(line);
  REQUIRE(r.ok());
  const auto& s = std::get<hmc::MotorStatus>(*r);
  CHECK(s == hmc::MotorStatus{1, hmc::MotorState::kMoving, -1600, 0, 1000, true, 1, false, 16});
  CHECK(hmc::describe(*r) ==
        "motor 1 moving at 1000 steps/s, at -1600 (1/256 step), toward 0, 1/16 step, homed, switch at end 0 pressed");
  CHECK(*hmc::encode_board_frame(*r) == line);
  const auto json = hmc::board_frame_to_json(*r);
  CHECK(json["state"] == "moving");
  CHECK(json["position"] == -1600);
  CHECK(json["microstep"] == 16);
}

TEST_CASE("events are told by their name") {
  auto evd = decode_board_frame("STX#5#EVD#1#2#1#1600#68#ETX");
  REQUIRE(evd.ok());
  CHECK(hmc::is_event(*evd));
  CHECK(hmc::describe(*evd) == "motor 1 stopped at -1600 (1/256 step)");
  auto evh = decode_board_frame("STX#5#EVH#2#1#0#0#3#ETX");
  REQUIRE(evh.ok());
  CHECK(hmc::describe(*evh) == "motor 2 homed at 0 (1/256 step)");
  auto evf = decode_board_frame("STX#3#EVF#2#3#5#ETX");
  REQUIRE(evf.ok());
  CHECK(hmc::describe(*evf) == "motor 2 driver fault: OTS, AOCP (STATUS 0x03)");
  auto evb = decode_board_frame("STX#3#EVB#2#100#102#ETX");
  REQUIRE(evb.ok());
  CHECK(std::get<hmc::Booted>(*evb) == hmc::Booted{2, 100});
  CHECK(hmc::describe(*evb) == "the board booted: protocol 2, firmware 0.1.0; checksums: the seed's sum");
}

TEST_CASE("VER, STB, STL and SET in words") {
  auto ver = decode_board_frame("STX#9#VER#2#100#0#128#50000#322#3#0#" +
                                std::to_string((2 + 100 + 128 + 50000 + 322 + 3) % 256) + "#ETX");
  REQUIRE(ver.ok());
  CHECK(hmc::describe(*ver) ==
        "protocol 2, firmware 0.1.0, 3 motors, 2 servos, 2 LED strips, limit switches on motors 1 and 2, lines up to "
        "128 bytes, up to 50000 steps/s, checksums: the seed's sum");
  auto stb = decode_board_frame("STX#5#STB#0#9#1472#0#" + std::to_string((9 + 1472) % 256) + "#ETX");
  REQUIRE(stb.ok());
  CHECK(std::get<hmc::BoardStatus>(*stb).limit_pressed(2, 1));
  CHECK(hmc::describe(*stb) ==
        "emergency switch released; limit switches pressed: motor 1 end 0, motor 2 end 1; servo 1 at 1472 us, servo 2 "
        "released");
  auto set = decode_board_frame("STX#4#SET#3#4#50000#" + std::to_string((3 + 4 + 50000) % 256) + "#ETX");
  REQUIRE(set.ok());
  CHECK(hmc::describe(*set) == "stepper 3: max_rate (fastest accepted move, steps/s) is 50000");
}

TEST_CASE("VER: both step budgets from protocol 7, eight values from an older board") {
  const std::string v7 = "STX#10#VER#7#100#0#128#50000#322#3#0#40000#" +
                         std::to_string((7 + 100 + 128 + 50000 + 322 + 3 + 40000) % 256) + "#ETX";
  auto now = decode_board_frame(v7);
  REQUIRE(now.ok());
  const auto& ver = std::get<hmc::Version>(*now);
  CHECK(ver.max_rate == 50000);
  CHECK(ver.max_ramping_rate == std::optional<uint32_t>(40000));
  CHECK(hmc::describe(*now).find("up to 50000 steps/s (40000 while a motor ramps)") != std::string::npos);
  CHECK(hmc::encode_board_frame(*now).value() == v7);
  CHECK(hmc::board_frame_to_json(*now)["max_ramping_rate"] == 40000);

  const std::string v6 = "STX#9#VER#6#100#0#128#50000#322#3#0#" +
                         std::to_string((6 + 100 + 128 + 50000 + 322 + 3) % 256) + "#ETX";
  auto older = decode_board_frame(v6);
  REQUIRE(older.ok());  // no decode error: the form a protocol-6 board sends
  CHECK(std::get<hmc::Version>(*older).protocol == 6);
  CHECK_FALSE(std::get<hmc::Version>(*older).max_ramping_rate.has_value());
  CHECK(hmc::describe(*older).find("up to 50000 steps/s, checksums") != std::string::npos);
  CHECK(hmc::encode_board_frame(*older).value() == v6);  // written back in its own form
  CHECK(hmc::board_frame_values(*older).value().count == 8);
  CHECK(hmc::board_frame_to_json(*older)["max_ramping_rate"].is_null());
  // The same in CRC-16 mode.
  auto crc = hmc::encode_board_frame(*older, ChecksumMode::kCrc16);
  REQUIRE(crc.ok());
  CHECK(decode_board_frame(*crc, ChecksumMode::kCrc16).value() == *older);

  // A board of protocol 7 must report both.
  const auto missing = refusal("STX#9#VER#7#100#0#128#50000#322#3#0#" +
                               std::to_string((7 + 100 + 128 + 50000 + 322 + 3) % 256) + "#ETX");
  CHECK(missing.reason == Reason::kBadLength);
  CHECK(missing.token == 1);
  CHECK(missing.offset == 4);
  CHECK(missing.expected == 10);
  CHECK(missing.found == 9);
  CHECK(missing.message ==
        "VER of protocol 7 has 10 fields (both step budgets, since protocol 7) but the length field says 9");
  // Any other length is refused naming both forms.
  const auto short_ver = refusal("STX#8#VER#6#100#0#128#50000#322#3#0#ETX");
  CHECK(short_ver.reason == Reason::kBadLength);
  CHECK(short_ver.message.find("VER has 10 fields (its name and 9 values; 9 from an older board)") != std::string::npos);
}

TEST_CASE("board frames follow the order of checks") {
  const auto unknown = refusal("STX#6#STM#1#1#128#1000#500#94#ETX");
  CHECK(unknown.reason == Reason::kUnknownCommand);
  CHECK(unknown.token == 2);
  CHECK(unknown.offset == 6);
  CHECK(unknown.message.find("STM is one of the commands (host to board)") != std::string::npos);
  // Unknown name before the name's length.
  CHECK(refusal("STX#2#XYZ#1#1#ETX").reason == Reason::kUnknownCommand);
  const auto length = refusal("STX#2#ACK#1#1#ETX");
  CHECK(length.reason == Reason::kBadLength);
  CHECK(length.expected == 1);
  CHECK(length.found == 2);
  // Checksum before range.
  CHECK(refusal("STX#2#EVE#2#3#ETX").reason == Reason::kChecksumMismatch);
  const auto range = refusal("STX#2#EVE#2#2#ETX");
  CHECK(range.reason == Reason::kOutOfRange);
  CHECK(range.token == 3);
  CHECK(range.field == "pressed");
  // A setting's value by the setting's range.
  const auto value = refusal("STX#4#SET#1#2#6#9#ETX");
  CHECK(value.reason == Reason::kOutOfRange);
  CHECK(value.token == 5);
  CHECK(value.message == "value is 6: expected 0-5 for setting 2 (decay)");
  // CRC mode: a checksum above 65535, the seed's sum.
  CHECK(refusal("STX#1#ACK#65536#ETX", ChecksumMode::kCrc16).reason == Reason::kOutOfRange);
  const auto sum = refusal("STX#1#ACK#00000#ETX", ChecksumMode::kCrc16);
  CHECK(sum.reason == Reason::kChecksumMismatch);
  CHECK(sum.expected == 20688);
  // CRC mode: the checksum field is exactly 5 digits.
  for (const char* line : {"STX#1#ACK#0#ETX", "STX#1#ACK#2068#ETX", "STX#1#ACK#020688#ETX"}) {
    INFO(line);
    const auto width = refusal(line, ChecksumMode::kCrc16);
    CHECK(width.reason == Reason::kBadNumber);
    CHECK(width.token == 3);
    CHECK(width.message.find("in CRC-16 mode the checksum is exactly 5 digits") != std::string::npos);
  }
}

TEST_CASE("encode_board_frame refuses what the wire cannot carry") {
  auto far = hmc::encode_board_frame(hmc::MotionEnded{1, hmc::MotionEnd::kCompleted, int64_t{1} << 31});
  REQUIRE_FALSE(far.ok());
  CHECK(far.error().reason == Reason::kOutOfRange);
  CHECK(far.error().field == "pos");
  hmc::MotorStatus odd;
  odd.microstep = 3;
  auto bad_microstep = hmc::encode_board_frame(odd);
  REQUIRE_FALSE(bad_microstep.ok());
  CHECK(bad_microstep.error().field == "flags");
  auto motor = hmc::encode_board_frame(hmc::LimitChanged{4, 0, true});
  REQUIRE_FALSE(motor.ok());
  CHECK(motor.error().field == "motor");
  CHECK(*hmc::encode_board_frame(hmc::MotionEnded{1, hmc::MotionEnd::kCompleted, -2147483647}) ==
        "STX#5#EVD#1#1#1#2147483647#" + std::to_string((1 + 1 + 1 + 2147483647u) % 256) + "#ETX");
  CHECK(*hmc::encode_board_frame(hmc::Ack{}, ChecksumMode::kCrc16) == "STX#1#ACK#20688#ETX");
}

TEST_CASE("EVR and STR: the reset cause, and where a fault happened, in words") {
  auto power_on = decode_board_frame("STX#6#EVR#1#0#0#0#0#1#ETX");
  REQUIRE(power_on.ok());
  CHECK(hmc::is_event(*power_on));
  CHECK(hmc::describe(*power_on) == "the board reset by power-on");
  auto watchdog = decode_board_frame("STX#6#STR#4#0#0#0#0#4#ETX");
  REQUIRE(watchdog.ok());
  CHECK_FALSE(hmc::is_event(*watchdog));
  CHECK(hmc::describe(*watchdog) == "last reset: the watchdog (the firmware's main loop stalled)");
  // A HardFault at 0x21A4 in the step interrupt (TC4: exception 35), called from 0x2173.
  auto fault = decode_board_frame("STX#6#EVR#6#3#8612#8563#35#67#ETX");
  REQUIRE(fault.ok());
  const auto& r = std::get<hmc::ResetEvent>(*fault);
  CHECK(r.cause == hmc::proto::ResetCause::kFault);
  CHECK(hmc::describe(*fault) ==
        "the board reset by a fault (HardFault) at pc 0x000021A4, lr 0x00002173, in interrupt 19");
  // An interrupt without a handler (exception 16 + 7), in the main loop; LR an exception return
  // (0xFFFFFFF9, bit 31 dropped on the wire).
  hmc::ResetStatus unhandled;
  unhandled.cause = hmc::proto::ResetCause::kFault;
  unhandled.exception = 23;
  unhandled.pc = 0x2400;
  unhandled.lr = 0x7FFFFFF9;
  CHECK(hmc::describe(unhandled) ==
        "last reset: a fault (interrupt 7 had no handler) at pc 0x00002400, lr 0xFFFFFFF9, in the main loop");
  auto encoded = hmc::encode_board_frame(unhandled);
  REQUIRE(encoded.ok());
  CHECK(encoded.value() == "STX#6#STR#6#23#9216#2147483641#0#" +
                               std::to_string((6 + 23 + 9216 + 2147483641ull) % 256) + "#ETX");
  // A cause this host does not know is out of range, not a crash.
  auto unknown = decode_board_frame("STX#6#EVR#9#0#0#0#0#9#ETX");
  REQUIRE_FALSE(unknown.ok());
  CHECK(unknown.error().reason == hmc::proto::Reason::kOutOfRange);
}
