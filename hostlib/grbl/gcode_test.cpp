// The G-code interpreter: words, modal state, grbl's error numbers, arcs within the tolerance.
#include <catch2/catch.hpp>

#include <cmath>
#include <set>

#include "hmc/gcode.h"

using namespace hmc::grbl;

namespace {

GrblResult<std::vector<Step>> run(Interpreter& in, const std::string& line, bool jog = false) {
  const CleanLine c = clean_line(line);
  REQUIRE_FALSE(c.garbage);
  return in.interpret(c.text, jog);
}

int error_of(Interpreter& in, const std::string& line) {
  GrblResult<std::vector<Step>> r = run(in, line);
  REQUIRE_FALSE(r.ok());
  return r.error().code;
}

const Move& move_at(const std::vector<Step>& steps, size_t i) { return std::get<Move>(steps.at(i)); }

}  // namespace

TEST_CASE("clean_line drops comments and blanks, upper-cases, counts what grbl stores") {
  CleanLine c = clean_line("g1 x10 (a comment) y2.5 ; the rest");
  CHECK(c.text == "G1X10Y2.5");
  CHECK(c.stored == 9);
  CHECK_FALSE(c.garbage);
  c = clean_line("G1 X\x01" "1");
  REQUIRE(c.garbage);
  CHECK(c.garbage->code == kExpectedCommandLetter);
  CHECK(c.garbage->message.find("0x01 at column 5") != std::string::npos);
  CHECK(clean_line("G0 X\xC3\xA9").garbage);
}

TEST_CASE("moves: absolute, incremental, inches, work offsets, G53") {
  Interpreter in;
  GrblResult<std::vector<Step>> r = run(in, "G0 X10 Y20");
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).rapid);
  CHECK(move_at(*r, 0).target == Vec3{10, 20, 0});
  CHECK(error_of(in, "G1 X5") == kUndefinedFeedRate);
  r = run(in, "G1 X5 F600");
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).feed == 600);
  CHECK(move_at(*r, 0).target == Vec3{5, 20, 0});
  REQUIRE(run(in, "G91 G20 X1").ok());
  CHECK(in.position()[0] == Approx(30.4));
  REQUIRE(run(in, "G90 G21 G92 X0 Y0").ok());  // here is 0,0 from now on
  CHECK(in.work_offset()[0] == Approx(30.4));
  r = run(in, "G0 X1");
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).target[0] == Approx(31.4));
  r = run(in, "G53 G0 X1");
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).target[0] == Approx(1));
  REQUIRE(run(in, "G10 L20 P1 X0").ok());  // G54 so that here is X0 (with G92's offset)
  CHECK(in.work_offset()[0] == Approx(1));
  CHECK(in.parser_state() == "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F600 S0]");
}

TEST_CASE("grbl's error numbers for bad lines") {
  Interpreter in;
  CHECK(error_of(in, "X") == kBadNumberFormat);
  CHECK(error_of(in, "1X") == kExpectedCommandLetter);
  CHECK(error_of(in, "G0 G1 X1") == kModalGroupViolation);
  CHECK(error_of(in, "G0 X1 X2") == kWordRepeated);
  CHECK(error_of(in, "G1.5 X1") == kCommandValueNotInteger);
  CHECK(error_of(in, "F-100") == kNegativeValue);
  CHECK(error_of(in, "G4") == kValueWordMissing);
  CHECK(error_of(in, "N99999999 G0 X1") == kInvalidLineNumber);
  CHECK(error_of(in, "G53 G2 X1 I1") == kG53InvalidMotionMode);
  CHECK(error_of(in, "G80 X1") == kAxisWordsExist);
  CHECK(error_of(in, "G0 X1 R5") == kUnusedWords);
  CHECK(error_of(in, "G10 L2 P9 X0") == kUnsupportedCoordSys);
  for (const char* line : {"M3 S1000", "M8", "T1 M6", "G28", "G18", "G38.2 Z-5", "A5", "G1 E3 F100", "S100", "G5 X1"}) {
    INFO(line);
    Interpreter fresh;
    GrblResult<std::vector<Step>> r = run(fresh, line);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().code == kUnsupportedCommand);
  }
  GrblResult<std::vector<Step>> r = run(in, "G0 A5");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("A5") != std::string::npos);  // the word is named
  CHECK(in.position() == Vec3{0, 0, 0});  // nothing of a refused line applies
}

TEST_CASE("arcs are split into chords within the tolerance and end exactly") {
  Interpreter in;
  REQUIRE(run(in, "G1 X10 Y0 F300").ok());
  GrblResult<std::vector<Step>> r = run(in, "G3 X0 Y10 I-10 J0");  // a quarter circle, centre 0,0
  REQUIRE(r.ok());
  // chord angle 2 acos(1 - 0.01/10) = 0.0894 rad: a quarter turn in 18 chords
  CHECK(r->size() == 18);
  for (const Step& s : *r) {
    const Move& m = std::get<Move>(s);
    CHECK(std::hypot(m.target[0], m.target[1]) == Approx(10).margin(1e-9));
    CHECK(m.feed == 300);
  }
  CHECK(move_at(*r, r->size() - 1).target == Vec3{0, 10, 0});
  r = run(in, "G2 X10 Y0 R10");  // back, clockwise, by radius
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).target[0] > 0);
  CHECK(move_at(*r, r->size() - 1).target == Vec3{10, 0, 0});
  CHECK(error_of(in, "G2 X0 Y10 I-3 J0") == kInvalidTarget);  // the end is not on the circle
  CHECK(error_of(in, "G2 X0 Y10") == kNoOffsetsInPlane);
  CHECK(error_of(in, "G2 X40 R5") == kInvalidTarget);
}

TEST_CASE("Marlin's servo and LED commands count from 0") {
  Interpreter in;
  GrblResult<std::vector<Step>> r = run(in, "M280 P1 S135");
  REQUIRE(r.ok());
  CHECK(std::get<ServoCommand>(r->at(0)).servo == 2);
  CHECK(std::get<ServoCommand>(r->at(0)).angle == 135);
  r = run(in, "M150 S0 R255 U128 B0 W10 P128");
  REQUIRE(r.ok());
  const LedCommand led = std::get<LedCommand>(r->at(0));
  CHECK(led.strip == 1);
  CHECK(led.r == 128);
  CHECK(led.g == 64);
  CHECK(led.w == 5);
  CHECK(error_of(in, "M280 P2 S90") == kUnsupportedCommand);
  CHECK(error_of(in, "M280 P0 S200") == kUnsupportedCommand);
  CHECK(error_of(in, "M150 S0 R300") == kUnsupportedCommand);
  CHECK(error_of(in, "M280 P0") == kValueWordMissing);
}

TEST_CASE("a jog's modes apply to the jog only") {
  Interpreter in;
  GrblResult<std::vector<Step>> r = run(in, "G91 G20 X1 F10", true);
  REQUIRE(r.ok());
  CHECK(move_at(*r, 0).target[0] == Approx(25.4));
  CHECK(move_at(*r, 0).feed == Approx(254));
  CHECK_FALSE(in.modal().incremental);
  CHECK_FALSE(in.modal().inches);
  GrblResult<std::vector<Step>> no_feed = in.interpret("G91X1", true);
  REQUIRE_FALSE(no_feed.ok());
  CHECK(no_feed.error().code == kUndefinedFeedRate);
  Interpreter j;
  GrblResult<std::vector<Step>> bad = run(j, "G1 X1 F10", true);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().code == kInvalidJog);
}

TEST_CASE("random lines: never a crash, grbl's numbers only, a refused line changes nothing") {
  const std::string alphabet = "GMXYZFIJKLNPRSTUBWA0123456789.-+ ()$=;%\t\x01\x7f\x80\xff";
  uint32_t seed = 12345;
  const auto next = [&seed] {
    seed = seed * 1103515245u + 12345u;
    return (seed >> 16) & 0x7fffu;
  };
  const std::set<int> known = {1, 2, 4, 16, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32, 33, 34, 35, 36};
  Interpreter in;
  size_t accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string line;
    const size_t length = next() % 24;
    for (size_t k = 0; k < length; ++k) line.push_back(alphabet[next() % alphabet.size()]);
    const CleanLine c = clean_line(line);
    if (c.garbage) {
      CHECK(c.garbage->code == kExpectedCommandLetter);
      continue;
    }
    const Interpreter before = in;
    GrblResult<std::vector<Step>> r = in.interpret(c.text, next() % 8 == 0);
    if (r) {
      ++accepted;
      for (const Step& s : *r) {
        if (const auto* m = std::get_if<Move>(&s)) {
          for (double v : m->target) CHECK(std::isfinite(v));
        }
      }
    } else {
      INFO(line);
      CHECK(known.count(r.error().code) == 1);
      CHECK(in.position() == before.position());
      CHECK(in.parser_state() == before.parser_state());
    }
  }
  CHECK(accepted > 0);
}
