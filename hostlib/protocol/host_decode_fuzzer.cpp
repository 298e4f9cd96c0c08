// Fuzzes the host codec: arbitrary bytes through LineSplitter and decode(), through decode() as
// one line, and through parse_input(). Besides crashes and undefined behaviour it checks:
//   - the stream cut into 2-3 pieces (sizes derived from the first byte), fed whole and fed
//     byte by byte gives the same lines and the same verdicts;
//   - finish() adds exactly the last unterminated line, when it is not ignored;
//   - a refusal has a reason, a message, an offset within the line, and token "none" exactly
//     for line_too_long;
//   - an accepted command round-trips: encode() succeeds, decode(encode(c)) == c and is
//     canonical, encode() of that is the same frame, and a canonical input is that frame;
//   - parse_input() accepts only commands that validate and encode, and explains refusals;
//   - the one-pass reading of canonical frames accepts only what the step-by-step reading
//     accepts as canonical, with the same command and values, in either checksum mode.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "frame_grammar.h"
#include "fuzz_support.h"
#include "hmc/line_splitter.h"

namespace {

using hmc::fuzz::escape;
using hmc::fuzz::outcome_of;
using hmc::fuzz::require;
using hmc::fuzz::to_string;
namespace proto = hmc::proto;

// Everything the host reports for one line, as text, so sequences compare exactly.
std::string render(const hmc::Line& line, const hmc::Result<hmc::Decoded, hmc::Diagnostic>& verdict) {
  std::string out = "#" + std::to_string(line.number) + " len=" + std::to_string(line.length) + " \"" +
                    escape(line.text) + "\" -> " + to_string(outcome_of(verdict));
  if (verdict) {
    out += verdict->canonical ? " canonical" : " not-canonical";
    for (const hmc::Warning& w : verdict->warnings) out += " warn:" + w.field + ":" + w.message;
  } else {
    out += " field=" + verdict.error().field + " message=" + verdict.error().message;
  }
  return out;
}

// A command the codec accepted must encode, decode back to itself and be a fixed point.
void check_round_trip(const hmc::Command& command, std::string_view input, const char* where) {
  auto what = [&] { return std::string(where) + ": " + to_string(hmc::fuzz::values_of(command)); };
  require(hmc::validate(command).ok(), [&] { return what() + " does not validate"; }, input);
  const auto frame = hmc::encode(command);
  require(frame.ok(), [&] { return what() + " does not encode"; }, input);
  const auto again = hmc::decode(*frame);
  require(again.ok(),
          [&] {
            return what() + " encodes to \"" + escape(*frame) + "\", which decode refuses: " + again.error().message;
          },
          input);
  require(again->command == command,
          [&] {
            return what() + " encodes to \"" + escape(*frame) + "\", which decodes to " +
                   to_string(hmc::fuzz::values_of(again->command));
          },
          input);
  require(again->canonical, [&] { return what() + ": encode wrote \"" + escape(*frame) + "\", not canonical"; },
          input);
  const auto canonical_again = hmc::encode(again->command);
  require(canonical_again.ok() && *canonical_again == *frame,
          [&] { return what() + ": encode of the canonical form differs from \"" + escape(*frame) + "\""; }, input);
}

// decode()'s verdict on `line`, which may end in the one terminator decode() removes.
void check_decoded(std::string_view line, const hmc::Result<hmc::Decoded, hmc::Diagnostic>& verdict,
                   std::string_view input, const char* where) {
  if (verdict) {
    check_round_trip(verdict->command, input, where);
    if (verdict->canonical) {
      std::string_view body = line;
      if (!body.empty() && body.back() == '\n') body.remove_suffix(1);
      if (!body.empty() && body.back() == '\r') body.remove_suffix(1);
      const auto frame = hmc::encode(verdict->command);
      require(frame.ok() && *frame == body,
              [&] {
                return std::string(where) + ": line \"" + escape(body) + "\" is called canonical but encodes to \"" +
                       (frame.ok() ? escape(*frame) : std::string("?")) + "\"";
              },
              input);
    }
    return;
  }
  const hmc::Diagnostic& d = verdict.error();
  auto what = [&] { return std::string(where) + ": " + to_string(outcome_of(verdict)); };
  require(d.reason != proto::Reason::kOk, [&] { return what() + ": refusal without a reason"; }, input);
  require(!d.message.empty(), [&] { return what() + ": refusal without a message"; }, input);
  require(d.offset <= line.size(),
          [&] { return what() + ": offset beyond the line's " + std::to_string(line.size()) + " bytes"; }, input);
  require((d.token == hmc::kNoToken) == (d.reason == proto::Reason::kLineTooLong),
          [&] { return what() + ": token none must mean line_too_long"; }, input);
}

// The stream's lines and their verdicts, fed in pieces ending at `cuts` (no finish()). With
// `check`, every line and verdict is also held to the invariants above.
std::vector<std::string> verdicts_of(std::string_view stream, const std::vector<std::size_t>& cuts, bool check,
                                     std::string_view input) {
  hmc::LineSplitter splitter;
  std::vector<std::string> out;
  std::size_t from = 0;
  auto drain = [&] {
    while (auto line = splitter.next()) {
      const auto verdict = hmc::decode(line->text);
      if (check) {
        require(line->text.size() == std::min<std::size_t>(line->length, proto::kLineMax + 1),
                [&] {
                  return "line keeps " + std::to_string(line->text.size()) + " of its " +
                         std::to_string(line->length) + " bytes";
                },
                input);
        check_decoded(line->text, verdict, input, "stream line");
      }
      out.push_back(render(*line, verdict));
    }
  };
  for (std::size_t cut : cuts) {
    splitter.feed(stream.substr(from, cut - from));
    drain();
    from = cut;
  }
  splitter.feed(stream.substr(from));
  drain();
  return out;
}

// Whether the stream ends in a line without its terminator that is not ignored.
bool ends_in_unfinished_line(std::string_view stream) {
  const std::size_t last_end = stream.find_last_of("\r\n");
  const std::string_view tail = last_end == std::string_view::npos ? stream : stream.substr(last_end + 1);
  return tail.size() > proto::kLineMax || !hmc::is_blank(tail);
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n       " + l;
  return lines.empty() ? "\n       (no lines)" : out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view input = hmc::fuzz::as_text(data, size);

  // The stream in one piece, then in 2-3 pieces whose sizes come from the first byte.
  const std::vector<std::string> whole = verdicts_of(input, {}, true, input);
  if (size > 0) {
    const uint8_t shape = data[0];
    std::vector<std::size_t> cuts;
    const std::size_t first = size * ((shape >> 1) & 0x7u) / 7;
    cuts.push_back(first);
    if ((shape & 1u) != 0) cuts.push_back(first + (size - first) * ((shape >> 4) & 0xFu) / 15);
    const std::vector<std::string> pieces = verdicts_of(input, cuts, false, input);
    require(pieces == whole,
            [&] {
              std::string at;
              for (std::size_t cut : cuts) at += " " + std::to_string(cut);
              return "cut at" + at + " gives:" + joined(pieces) + "\n     whole gives:" + joined(whole);
            },
            input);
  }
  std::vector<std::size_t> every_byte;
  for (std::size_t i = 1; i < size; ++i) every_byte.push_back(i);
  const std::vector<std::string> bytewise = verdicts_of(input, every_byte, false, input);
  require(bytewise == whole,
          [&] { return "byte by byte gives:" + joined(bytewise) + "\n     whole gives:" + joined(whole); }, input);

  // finish() completes the last line, if it has no terminator and is not ignored.
  {
    hmc::LineSplitter splitter;
    splitter.feed(input);
    while (splitter.next()) {
    }
    splitter.finish();
    std::size_t more = 0;
    while (splitter.next()) ++more;
    require(more == (ends_in_unfinished_line(input) ? 1u : 0u),
            [&] { return "finish() gave " + std::to_string(more) + " more lines"; }, input);
  }

  // The one-pass reading agrees with the step by step one wherever it accepts.
  for (const proto::ChecksumMode mode : {proto::ChecksumMode::kSum, proto::ChecksumMode::kCrc16}) {
    namespace g = hmc::grammar;
    std::array<uint32_t, proto::kMaxValues> values{};
    const g::Shape* shape = g::parse_canonical_frame(input, mode, g::command_shapes(), values);
    if (shape == nullptr) continue;
    const auto slow = g::parse_frame(input, mode, g::command_shapes());
    require(slow.ok(), [&] { return "one-pass reading accepts what parse_frame refuses: " + slow.error().message; },
            input);
    require(g::find_fault(*shape, values.data()).reason == proto::Reason::kOk,
            [&] { return std::string("one-pass reading accepts values find_fault refuses"); }, input);
    require(slow->shape == shape && slow->canonical && slow->values == values,
            [&] { return std::string("one-pass reading differs from parse_frame"); }, input);
  }

  // The input as one line, and as what a person types.
  check_decoded(input, hmc::decode(input), input, "one line");
  const auto typed = hmc::parse_input(input);
  if (typed) {
    check_round_trip(*typed, input, "parse_input");
  } else {
    const hmc::Diagnostic& d = typed.error();
    auto what = [&] {
      return "parse_input: " + to_string(outcome_of(hmc::Result<hmc::Decoded, hmc::Diagnostic>(d)));
    };
    require(d.reason != proto::Reason::kOk, [&] { return what() + ": refusal without a reason"; }, input);
    require(!d.message.empty(), [&] { return what() + ": refusal without a message"; }, input);
    require(d.offset <= size, [&] { return what() + ": offset beyond the input"; }, input);
  }
  return 0;
}
