// Fuzzes the firmware's FrameParser as the UART drives it: arbitrary bytes through feed(), one at
// a time. Besides crashes and undefined behaviour it checks, for every verdict:
//   - offset <= 128, and token is "none" exactly for line_too_long;
//   - a verdict comes at a line end exactly when the line is not ignored (CR and LF each end a
//     line; a line of only spaces and tabs up to 128 bytes is ignored; the last, unterminated
//     line gets none), so the verdict count is the number of such lines;
//   - the verdict equals what parse_line() gives for the same line;
//   - an accepted command re-encodes (host encode) to a frame that the host decode and
//     parse_line() both accept as the very same command.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"

namespace {

using hmc::fuzz::Outcome;
using hmc::fuzz::outcome_of;
using hmc::fuzz::require;
using hmc::fuzz::to_string;
namespace proto = hmc::proto;

// The line being received, as this harness sees it, independent of the parser.
struct LineTracker {
  std::string bytes;  // the line's first kLineMax bytes
  std::size_t length = 0;
  bool blank = true;

  void add(uint8_t byte) {
    if (length < proto::kLineMax) bytes += static_cast<char>(byte);
    ++length;
    blank = blank && (byte == ' ' || byte == '\t');
  }
  bool gets_verdict() const { return length > proto::kLineMax || !blank; }
  void clear() { *this = LineTracker{}; }
};

void check_accepted(const hmc::fw::Verdict& verdict, std::string_view input) {
  const hmc::fuzz::Values fw = hmc::fuzz::values_of(verdict.command);
  const hmc::Command command = hmc::make_command(fw.id, fw.v);

  const auto frame = hmc::encode(command);
  require(frame.ok(), [&] { return "host encode refuses the accepted command " + to_string(fw) + ": " +
                                 frame.error().message; }, input);

  const auto decoded = hmc::decode(*frame);
  require(decoded.ok() && hmc::fuzz::same_values(hmc::fuzz::values_of(decoded->command), fw),
          [&] {
            return "host decode of the re-encoded frame \"" + hmc::fuzz::escape(*frame) + "\" gives " +
                   to_string(outcome_of(decoded)) + ", firmware accepted " + to_string(fw);
          },
          input);

  hmc::fw::Verdict again{};
  const bool judged = hmc::fw::FrameParser::parse_line(reinterpret_cast<const uint8_t*>(frame->data()),
                                                        static_cast<uint32_t>(frame->size()), again);
  require(judged && outcome_of(again) == outcome_of(verdict),
          [&] {
            return "parse_line of the re-encoded frame \"" + hmc::fuzz::escape(*frame) + "\" gives " +
                   (judged ? to_string(outcome_of(again)) : std::string("no verdict")) + ", feed accepted " +
                   to_string(fw);
          },
          input);
}

void check_verdict(const hmc::fw::Verdict& verdict, const LineTracker& line, std::string_view input) {
  const Outcome outcome = outcome_of(verdict);
  require(verdict.offset <= proto::kLineMax,
          [&] { return "offset " + std::to_string(verdict.offset) + " > 128: " + to_string(outcome); }, input);
  require((verdict.token == proto::kNoToken) == (verdict.reason == proto::Reason::kLineTooLong),
          [&] { return "token none must mean line_too_long: " + to_string(outcome); }, input);

  // The same line judged whole; beyond the limit the parser never reads past kLineMax bytes.
  hmc::fw::Verdict whole{};
  const bool judged = hmc::fw::FrameParser::parse_line(reinterpret_cast<const uint8_t*>(line.bytes.data()),
                                                        static_cast<uint32_t>(line.length), whole);
  require(judged && outcome_of(whole) == outcome,
          [&] {
            return "feed gives " + to_string(outcome) + " but parse_line of the line gives " +
                   (judged ? to_string(outcome_of(whole)) : std::string("no verdict"));
          },
          input);

  if (verdict.reason == proto::Reason::kOk) check_accepted(verdict, input);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view input = hmc::fuzz::as_text(data, size);
  hmc::fw::FrameParser parser;
  LineTracker line;
  std::size_t verdicts = 0;
  std::size_t lines_with_verdict = 0;

  for (std::size_t i = 0; i < size; ++i) {
    const uint8_t byte = data[i];
    const bool line_end = byte == '\r' || byte == '\n';
    const bool judged = parser.feed(byte);
    if (!line_end) {
      require(!judged, [&] { return "feed gave a verdict at byte " + std::to_string(i) + ", which ends no line"; },
              input);
      line.add(byte);
      continue;
    }
    const bool expected = line.gets_verdict();
    require(judged == expected,
            [&] {
              return "line ending at byte " + std::to_string(i) + (expected ? " got no verdict" : " got a verdict") +
                     " (" + std::to_string(line.length) + " bytes, " + (line.blank ? "blank" : "not blank") + ")";
            },
            input);
    lines_with_verdict += expected ? 1 : 0;
    if (judged) {
      ++verdicts;
      check_verdict(parser.verdict(), line, input);
    }
    line.clear();
  }
  require(verdicts == lines_with_verdict,
          [&] {
            return "verdict count " + std::to_string(verdicts) + " != " + std::to_string(lines_with_verdict) +
                   " lines that are not ignored";
          },
          input);
  return 0;
}
