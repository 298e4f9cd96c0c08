// FrameParser: the firmware's byte-at-a-time reader of command frames (docs/protocol.md).
//
// Bytes go in one at a time as the UART delivers them. At every line end the parser gives one
// verdict for the line: an accepted, typed Command, or a refusal with its reason, the token and
// byte offset it concerns, and expected/found values. Blank lines give no verdict. Whatever
// went wrong, the next line is parsed from a clean state.
//
// Freestanding: no heap, no exceptions, no library strings. The line buffer is
// proto::kLineMax (128) bytes, the longest frame the grammar allows plus room for blanks; see
// protocol_facts.h for the arithmetic. Longer lines are refused as line_too_long.
#pragma once

#include <stdint.h>

#include "crc16.h"
#include "protocol_facts.h"

namespace hmc::fw {

struct StepperCommand {
  uint8_t motor;       // 1..3
  uint8_t dir;         // proto::kActionStop / Forward / Reverse / Home
  uint32_t microstep;  // as received (not checked on stop)
  uint32_t steps;
  uint32_t delay_us;
};

struct ServoCommand {
  uint8_t servo;  // 1 pan, 2 tilt
  uint8_t angle;  // 10..170 degrees
};

struct LedCommand {
  uint8_t strip;  // 1..2
  uint8_t r, g, b, w;
};

// Protocol v2 (VER has no values).
struct StatusQuery {
  uint8_t unit;  // 1..3 motor, proto::kUnitBoard, strips from proto::kUnitFirstStrip
};

struct SettingCommand {  // SET, and GET with value 0
  uint8_t motor;
  uint8_t setting;  // proto::SettingId
  uint32_t value;
};

struct LimitsCommand {
  uint8_t motor;
  uint8_t low_sign;  // 0 plus, 1 minus
  uint32_t low;      // 1/256 step
  uint8_t high_sign;
  uint32_t high;
};

struct ChecksumModeCommand {
  uint8_t mode;  // proto::ChecksumMode
};

struct WatchdogCommand {  // protocol 3
  uint32_t timeout_ms;   // 0 off
};

struct PositionCommand {
  uint8_t motor;
  uint8_t sign;       // 0 plus, 1 minus
  uint32_t position;  // 1/256 step
};

struct Command {
  proto::CommandId id;
  union {
    StepperCommand stepper;
    ServoCommand servo;
    LedCommand led;
    StatusQuery status;
    SettingCommand setting;
    LimitsCommand limits;
    ChecksumModeCommand checksum_mode;
    WatchdogCommand watchdog;
    PositionCommand position;
  };
};

struct Verdict {
  proto::Reason reason;  // kOk: accepted and `command` holds it; otherwise refused
  uint8_t token;         // token index the refusal concerns, proto::kNoToken for none
  uint8_t offset;        // byte offset in the line, leading blanks included
  uint32_t expected;     // checksum_mismatch / bad_length; 0 otherwise
  uint32_t found;        // checksum_mismatch / bad_length / out_of_range; 0 otherwise
  Command command;       // valid only when reason == kOk
};

// A command's values in wire order (its command table's field order); returns how many.
uint32_t command_values(const Command& command, uint32_t (&values)[proto::kMaxValues]);

class FrameParser {
 public:
  FrameParser();

  // The checksum rule for lines from now on (the seed's sum at construction).
  void set_checksum_mode(proto::ChecksumMode mode) { mode_ = mode; }
  proto::ChecksumMode checksum_mode() const { return mode_; }

  // Takes the next byte of the stream. Returns true when it ended a non-blank line; the
  // line's verdict is then in verdict() until the next call.
  bool feed(uint8_t byte);

  // The verdict of the line feed() last completed.
  const Verdict& verdict() const { return verdict_; }
  // The byte offset of `token` in the line feed() last completed (leading blanks included),
  // for refusals the controller makes after the parser accepted the line. Valid until the next
  // feed(); the offset of the line's end when the line has fewer tokens.
  uint8_t token_offset(uint8_t token) const;

  // Judges one line (terminator excluded) of any length. Returns false for a blank line, which
  // gets no verdict. feed() uses this at every line end; tests and fuzzers may call it directly.
  static bool parse_line(const uint8_t* line, uint32_t length, Verdict& out,
                         proto::ChecksumMode mode = proto::ChecksumMode::kSum);

 private:
  uint8_t line_[proto::kLineMax];
  uint32_t length_;   // bytes received on the current line, counting those not stored
  uint32_t last_length_;  // stored bytes of the line last completed
  proto::ChecksumMode mode_;
  Verdict verdict_;
};

}  // namespace hmc::fw
