// Differential fuzzing of the two parsers of docs/protocol.md. The same bytes go
//   - as a stream: firmware FrameParser::feed() byte by byte against host LineSplitter + decode()
//     (no finish(): a line without its end has no verdict yet on either side);
//   - as one line: FrameParser::parse_line() against decode(). decode() removes one trailing
//     LF, CRLF or CR and refuses a blank line as bad_start; parse_line() gets the line with that
//     terminator removed and gives no verdict for a blank line.
// Both must give the same verdicts: accept/refuse, reason, token, offset, expected, found and
// every decoded field, in both checksum modes (the seed's sum and CRC-16; the CRC vectors of
// the seed corpus give the fuzzer frames with valid CRCs to mutate). On a disagreement both
// verdicts are printed with the input and the mode, and it aborts.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "hmc/line_splitter.h"

namespace {

using hmc::fuzz::Outcome;
using hmc::fuzz::outcome_of;
using hmc::fuzz::to_string;
namespace proto = hmc::proto;

using proto::ChecksumMode;

const char* mode_name(ChecksumMode mode) { return mode == ChecksumMode::kCrc16 ? "CRC-16" : "sum"; }

std::vector<Outcome> firmware_stream(const uint8_t* data, std::size_t size, ChecksumMode mode) {
  hmc::fw::FrameParser parser;
  parser.set_checksum_mode(mode);
  std::vector<Outcome> out;
  for (std::size_t i = 0; i < size; ++i) {
    if (parser.feed(data[i])) out.push_back(outcome_of(parser.verdict()));
  }
  return out;
}

std::vector<Outcome> host_stream(std::string_view stream, ChecksumMode mode) {
  hmc::LineSplitter splitter;
  splitter.feed(stream);
  std::vector<Outcome> out;
  while (auto line = splitter.next()) out.push_back(outcome_of(hmc::decode(line->text, mode)));
  return out;
}

Outcome firmware_line(std::string_view line, ChecksumMode mode) {
  hmc::fw::Verdict verdict{};
  if (!hmc::fw::FrameParser::parse_line(reinterpret_cast<const uint8_t*>(line.data()),
                                        static_cast<uint32_t>(line.size()), verdict, mode)) {
    return Outcome{};  // ignored
  }
  return outcome_of(verdict);
}

// decode()'s verdict, with its documented refusal of a blank line read as "ignored".
Outcome host_line(std::string_view input, std::string_view line, ChecksumMode mode) {
  const auto verdict = hmc::decode(input, mode);
  if (line.size() <= proto::kLineMax && hmc::is_blank(line)) {
    Outcome refusal = outcome_of(verdict);
    const bool documented = refusal.kind == Outcome::Kind::kRefused && refusal.reason == proto::Reason::kBadStart &&
                            refusal.token == 0 && refusal.offset == 0;
    if (!documented) {
      hmc::fuzz::fail("decode of a blank line should refuse it as bad_start token 0 offset 0, gives " +
                          to_string(refusal),
                      input);
    }
    return Outcome{};
  }
  return outcome_of(verdict);
}

// The comparisons in one checksum mode.
void compare(const uint8_t* data, std::size_t size, ChecksumMode mode) {
  const std::string_view input = hmc::fuzz::as_text(data, size);
  const std::string in_mode = std::string(" (") + mode_name(mode) + " mode)";

  const std::vector<Outcome> firmware = firmware_stream(data, size, mode);
  const std::vector<Outcome> host = host_stream(input, mode);
  if (firmware != host) {
    hmc::fuzz::fail("as a stream the parsers disagree" + in_mode + "\n     firmware:" + to_string(firmware) +
                        "\n     host:    " + to_string(host),
                    input);
  }

  std::string_view line = input;
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  const Outcome firmware_verdict = firmware_line(line, mode);
  const Outcome host_verdict = host_line(input, line, mode);
  if (firmware_verdict != host_verdict) {
    hmc::fuzz::fail("as one line the parsers disagree" + in_mode + "\n     firmware: " + to_string(firmware_verdict) +
                        "\n     host:     " + to_string(host_verdict),
                    input);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  compare(data, size, ChecksumMode::kSum);
  compare(data, size, ChecksumMode::kCrc16);
  return 0;
}
