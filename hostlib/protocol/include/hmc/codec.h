// The host codec: frames to typed commands and back, with diagnostics a person can act on.
//
// decode() judges one line exactly as docs/protocol.md's order of checks prescribes (the same
// verdict the firmware's FrameParser gives, by an independent algorithm) and adds a message
// naming what was wrong, where (byte offset and field) and what was expected. encode() writes
// the canonical frame, length and checksum filled in. parse_input() accepts what people type:
// a frame or the spec's command-set notation `[#STM#1#1#128#1000#500]`.
//
// Every function that reads or writes a checksum takes the checksum mode in force (protocol
// v2's `CRC` command): the seed's sum, the default, or CRC-16 (docs/protocol.md "CRC-16 mode").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/crc16.h"
#include "hmc/command.h"
#include "hmc/result.h"

namespace hmc {

inline constexpr int kNoToken = -1;

// Why a line or a command was refused.
struct Diagnostic {
  proto::Reason reason = proto::Reason::kOk;
  int token = kNoToken;     // token index the refusal concerns (docs/protocol.md "Frames")
  std::size_t offset = 0;   // byte offset in the line, leading blanks included
  uint32_t expected = 0;    // checksum_mismatch, bad_length
  uint32_t found = 0;       // checksum_mismatch, bad_length, out_of_range
  std::string field;        // the token's name: "checksum", "microstep", "length", ...
  std::string message;      // one sentence: what, expected vs found
};

// A value the spec's table advises against (the frame is still valid).
struct Warning {
  std::string field;
  std::string message;
};

struct Decoded {
  Command command;
  bool canonical = true;           // no leading zeros, nothing around the frame
  std::vector<Warning> warnings;   // lint of the command's values
};

// True when the line holds nothing but spaces and tabs: such a line gets no verdict.
bool is_blank(std::string_view line);

// Judges one line. One trailing LF, CRLF or CR is allowed and removed. A blank line is refused
// as bad_start ("no frame on the line"); stream readers skip blank lines before decoding.
Result<Decoded, Diagnostic> decode(std::string_view line, proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// Checks a command against the protocol's ranges and rules (steps 15-16 of the order of
// checks). Token and offset in the diagnostic refer to the frame encode() would write.
Result<Command, Diagnostic> validate(const Command& command);

// The values of a valid command the spec's table advises against.
std::vector<Warning> lint(const Command& command);

// The canonical frame for a command, without a line terminator; refuses an invalid command.
Result<std::string, Diagnostic> encode(const Command& command, proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// A frame written in place by encode_into(): room for kLineMax bytes and the whole words the
// writer stores past the frame's end.
struct FrameText {
  static constexpr std::size_t kRoom = proto::kLineMax + 32;
  std::array<char, kRoom> bytes;
  std::size_t size = 0;
  std::string_view view() const { return {bytes.data(), size}; }
};

// encode() into `out`, for loops that frame many commands: nothing allocated, nothing copied.
// Returns the frame's length; a refused command leaves no frame in `out` (size 0).
Result<std::size_t, Diagnostic> encode_into(const Command& command, FrameText& out,
                                            proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// A command as a person types it: a frame (`STX#...#ETX`) or command-set notation
// (`[#NAME#v1#...#vn]`, blanks around allowed; it has no checksum). Offsets refer to `text`.
Result<Command, Diagnostic> parse_input(std::string_view text, proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// A command from a name and its values as separate words (`STM 1 1 128 1000 500`, `VER`).
Result<Command, Diagnostic> command_from_words(const std::vector<std::string>& words);

// A command as one line of text in any of the forms above: a frame or command-set notation
// (the text holds a '#'), else words separated by blanks.
Result<Command, Diagnostic> command_from_text(std::string_view text, proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// The checksum field of the command's canonical frame: the sum of its values mod 256, or the
// CRC-16 of the frame's bytes before the checksum field.
uint32_t checksum(const Command& command, proto::ChecksumMode mode = proto::ChecksumMode::kSum);

}  // namespace hmc
