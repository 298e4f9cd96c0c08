// Fuzzes the host's reading of what the board sends: arbitrary bytes through LineSplitter and
// decode_board_frame(), in both checksum modes (the seed's sum and CRC-16), and the whole input
// as one line. Besides crashes, undefined behaviour and unbounded memory it checks:
//   - the stream fed whole and cut in two (where the first byte says) gives the same lines, and
//     each line keeps min(length, kLineMax + 1) bytes;
//   - a refusal has a reason, a message, an offset within the line, and token "none" exactly
//     for line_too_long;
//   - an accepted frame: board_frame_values() succeeds with the table's value count (VER: or
//     the 8 of a board before protocol 7);
//     encode_board_frame() in the same mode writes a line that decodes, in that mode, to an
//     equal frame and encodes back to itself; the same holds in the other mode; is_event()
//     agrees with the name (events start with 'E'); describe() gives words.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.h"
#include "hmc/board_frame.h"
#include "hmc/line_splitter.h"

namespace {

using hmc::fuzz::escape;
using hmc::fuzz::require;
namespace proto = hmc::proto;

constexpr proto::ChecksumMode kModes[] = {proto::ChecksumMode::kSum, proto::ChecksumMode::kCrc16};

const char* mode_name(proto::ChecksumMode mode) { return mode == proto::ChecksumMode::kCrc16 ? "crc16" : "sum"; }

proto::ChecksumMode other(proto::ChecksumMode mode) {
  return mode == proto::ChecksumMode::kCrc16 ? proto::ChecksumMode::kSum : proto::ChecksumMode::kCrc16;
}

// The typed frame must write itself in `mode` and read back the same.
void check_round_trip(const hmc::BoardFrame& frame, proto::ChecksumMode mode, std::string_view input,
                      const std::string& where) {
  const auto what = [&] { return where + " (" + mode_name(mode) + "): " + hmc::describe(frame); };
  const auto line = hmc::encode_board_frame(frame, mode);
  require(line.ok(), [&] { return what() + ": encode_board_frame refuses: " + line.error().message; }, input);
  const auto again = hmc::decode_board_frame(*line, mode);
  require(again.ok(),
          [&] { return what() + ": encodes to \"" + escape(*line) + "\", which is refused: " + again.error().message; },
          input);
  require(*again == frame,
          [&] { return what() + ": encodes to \"" + escape(*line) + "\", which decodes to " + hmc::describe(*again); },
          input);
  const auto line_again = hmc::encode_board_frame(*again, mode);
  require(line_again.ok() && *line_again == *line,
          [&] { return what() + ": \"" + escape(*line) + "\" does not encode back to itself"; }, input);
}

void check_decoded(std::string_view line, proto::ChecksumMode mode,
                   const hmc::Result<hmc::BoardFrame, hmc::Diagnostic>& verdict, std::string_view input,
                   const char* where) {
  const auto at = [&] { return std::string(where) + " \"" + escape(line) + "\" (" + mode_name(mode) + ")"; };
  if (!verdict) {
    const hmc::Diagnostic& d = verdict.error();
    require(d.reason != proto::Reason::kOk, [&] { return at() + ": refusal without a reason"; }, input);
    require(!d.message.empty(), [&] { return at() + ": refusal without a message"; }, input);
    require(d.offset <= line.size(),
            [&] { return at() + ": refusal offset " + std::to_string(d.offset) + " beyond the line"; }, input);
    require((d.token == hmc::kNoToken) == (d.reason == proto::Reason::kLineTooLong),
            [&] { return at() + ": token none must mean line_too_long (" + d.message + ")"; }, input);
    return;
  }
  const hmc::BoardFrame& frame = *verdict;
  const std::string words = hmc::describe(frame);
  require(!words.empty(), [&] { return at() + ": describe() gives nothing"; }, input);
  const proto::BoardFrameSpec& spec = hmc::board_frame_spec(frame);
  require(hmc::is_event(frame) == (spec.name[0] == 'E'),
          [&] { return at() + ": is_event() disagrees with the name " + std::string(spec.name); }, input);
  const auto values = hmc::board_frame_values(frame);
  require(values.ok(), [&] { return at() + ": board_frame_values refuses: " + values.error().message; }, input);
  const bool older_version = hmc::board_frame_id(frame) == proto::BoardFrameId::kVersion &&
                             values->count == proto::kVersionValuesBefore7;
  require(values->count == spec.value_count || older_version,
          [&] {
            return at() + ": board_frame_values gives " + std::to_string(values->count) + " values, not " +
                   std::to_string(spec.value_count);
          },
          input);
  check_round_trip(frame, mode, input, at());
  check_round_trip(frame, other(mode), input, at());
}

struct SplitLine {
  std::string text;
  std::size_t length;
  std::size_t number;
  bool operator==(const SplitLine& o) const { return text == o.text && length == o.length && number == o.number; }
};

// The stream's lines, fed in two pieces cut at `cut`, then finished.
std::vector<SplitLine> lines_of(std::string_view stream, std::size_t cut) {
  hmc::LineSplitter splitter;
  std::vector<SplitLine> out;
  auto drain = [&] {
    while (auto line = splitter.next()) out.push_back({line->text, line->length, line->number});
  };
  splitter.feed(stream.substr(0, cut));
  drain();
  splitter.feed(stream.substr(cut));
  drain();
  splitter.finish();
  drain();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view input = hmc::fuzz::as_text(data, size);

  const std::vector<SplitLine> lines = lines_of(input, size);
  if (size > 0) {
    const std::size_t cut = size * data[0] / 255;
    require(lines_of(input, cut) == lines,
            [&] { return "cutting the stream at " + std::to_string(cut) + " changes its lines"; }, input);
  }
  for (const SplitLine& line : lines) {
    require(line.text.size() == std::min<std::size_t>(line.length, proto::kLineMax + 1),
            [&] {
              return "line " + std::to_string(line.number) + " keeps " + std::to_string(line.text.size()) +
                     " of its " + std::to_string(line.length) + " bytes";
            },
            input);
    for (proto::ChecksumMode mode : kModes) {
      check_decoded(line.text, mode, hmc::decode_board_frame(line.text, mode), input, "line");
    }
  }
  for (proto::ChecksumMode mode : kModes) {
    check_decoded(input, mode, hmc::decode_board_frame(input, mode), input, "whole input");
  }
  return 0;
}
