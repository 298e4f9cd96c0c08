// Jog keys from a terminal's bytes and jog ends at the soft limits.
#include "hmc/jog.h"

#include <catch2/catch.hpp>

namespace hmc {
namespace {

using Kind = JogKey::Kind;

TEST_CASE("arrows, Page Up/Down and their Shift forms move the three axes") {
  std::string bytes = "\x1b[C\x1b[D\x1b[A\x1b[B\x1b[5~\x1b[6~\x1bOC\x1b[1;2C\x1b[1;2B\x1b[5;2~\x1b[1;5C";
  const std::vector<JogKey> keys = decode_jog_keys(bytes);
  const std::vector<JogKey> want{{Kind::kMove, 0, +1, false}, {Kind::kMove, 0, -1, false}, {Kind::kMove, 1, +1, false},
                                 {Kind::kMove, 1, -1, false}, {Kind::kMove, 2, +1, false}, {Kind::kMove, 2, -1, false},
                                 {Kind::kMove, 0, +1, false}, {Kind::kMove, 0, +1, true},  {Kind::kMove, 1, -1, true},
                                 {Kind::kMove, 2, +1, true},  {Kind::kMove, 0, +1, false}};  // Ctrl+Right: no Shift
  CHECK(keys == want);
  CHECK(bytes.empty());
}

TEST_CASE("the other keys; unknown bytes and sequences are dropped") {
  std::string bytes = "+-= zqx\x03\x1b[H\x1bx";
  const std::vector<JogKey> keys = decode_jog_keys(bytes);
  std::vector<Kind> kinds;
  for (const JogKey& k : keys) kinds.push_back(k.kind);
  CHECK(kinds == std::vector<Kind>{Kind::kStepUp, Kind::kStepDown, Kind::kStepUp, Kind::kStopAll, Kind::kZero,
                                   Kind::kQuit, Kind::kInterrupt});
  CHECK(bytes.empty());
}

TEST_CASE("a sequence split between two reads is decoded once whole") {
  std::string bytes = "q\x1b[1;";
  CHECK(decode_jog_keys(bytes).size() == 1);
  CHECK(bytes == "\x1b[1;");
  bytes += "2D";
  const std::vector<JogKey> keys = decode_jog_keys(bytes);
  REQUIRE(keys.size() == 1);
  CHECK(keys[0] == JogKey{Kind::kMove, 0, -1, true});
  CHECK(bytes.empty());
  bytes = "\x1b";
  CHECK(decode_jog_keys(bytes).empty());
  CHECK(bytes == "\x1b");
}

TEST_CASE("a window's named keys mean what the terminal's bytes mean") {
  std::string right = "\x1b[C", shift_page_down = "\x1b[6;2~";
  CHECK(jog_arrow_key(JogArrow::kRight, false) == decode_jog_keys(right).at(0));
  CHECK(jog_arrow_key(JogArrow::kPageDown, true) == decode_jog_keys(shift_page_down).at(0));
  CHECK(jog_arrow_key(JogArrow::kUp, false) == JogKey{JogKey::Kind::kMove, 1, +1, false});
  CHECK(jog_char_key('+')->kind == JogKey::Kind::kStepUp);
  CHECK(jog_char_key(' ')->kind == JogKey::Kind::kStopAll);
  CHECK(jog_char_key('z')->kind == JogKey::Kind::kZero);
  CHECK_FALSE(jog_char_key('x'));
}

TEST_CASE("a jog stops at the soft limit it would cross, once the limits apply") {
  Axis slide;
  slide.name = "slide";
  slide.limit_min = -50;
  slide.limit_max = 5;
  MotorStatus motor;
  motor.homed = true;
  CHECK(jog_end(slide, motor, 1, 1).target == 2);
  CHECK_FALSE(jog_end(slide, motor, 1, 1).at_limit);
  const JogEnd high = jog_end(slide, motor, 1, 10);
  CHECK(high.target == 5);
  CHECK(high.at_limit);
  const JogEnd low = jog_end(slide, motor, -45, -10);
  CHECK(low.target == -50);
  CHECK(low.at_limit);
  motor.homed = false;  // its position means nothing yet: no limits (as grbl)
  CHECK(jog_end(slide, motor, 1, 10).target == 11);
}

}  // namespace
}  // namespace hmc
