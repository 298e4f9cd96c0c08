// Unit tests of the stream splitter: terminators, blank lines, partial reads, bounded memory.
#include "hmc/line_splitter.h"

#include <catch2/catch.hpp>

#include "hmc/protocol_facts.h"

namespace {

std::vector<hmc::Line> all_lines(hmc::LineSplitter& s) {
  std::vector<hmc::Line> out;
  while (auto line = s.next()) out.push_back(*line);
  return out;
}

}  // namespace

TEST_CASE("LF, CRLF and lone CR each end one line; blank lines are dropped") {
  hmc::LineSplitter s;
  s.feed("a\nb\r\nc\rd\n\n  \t\r\ne");
  auto lines = all_lines(s);
  REQUIRE(lines.size() == 4);
  CHECK(lines[0].text == "a");
  CHECK(lines[1].text == "b");
  CHECK(lines[2].text == "c");
  CHECK(lines[3].text == "d");
  CHECK(lines[3].number == 4);
  s.finish();
  lines = all_lines(s);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].text == "e");
  CHECK(lines[0].number == 7);
}

TEST_CASE("a CRLF split across two reads is one line end") {
  hmc::LineSplitter s;
  s.feed("STX#3#SVM#1#10#11#ETX\r");
  s.feed("\nnext\n");
  auto lines = all_lines(s);
  REQUIRE(lines.size() == 2);
  CHECK(lines[1].text == "next");
  CHECK(lines[1].number == 2);
}

TEST_CASE("an endless line keeps bounded memory and its true length") {
  hmc::LineSplitter s;
  for (int i = 0; i < 1000; ++i) s.feed(std::string(1000, 'x'));
  s.feed("\nok\n");
  auto lines = all_lines(s);
  REQUIRE(lines.size() == 2);
  CHECK(lines[0].text.size() == hmc::proto::kLineMax + 1);
  CHECK(lines[0].length == 1000000);
  CHECK(lines[1].text == "ok");
}
