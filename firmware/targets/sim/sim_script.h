// Injected events for hmc-sim: the small command language shared by --script files and the
// control channel (docs/sim.md, "Injected events"), its parser, and what each command does to a
// SimBoard.
//
//   press M END | release M END | auto M END    force limit switch END (0, 1) of motor M (1, 2)
//   estop | estop release                        the emergency switch
//   fault M BITS                                 latch DRV8711 STATUS bits (0-255) of motor M
//   send TEXT                                    TEXT and a line feed, as if received on the link
//   status                                       control channel only: one JSON line of state
//
// A script line is `at TIME COMMAND`, a `#` comment or blank. TIME is virtual time since
// power-up: `1.5s`, `250ms`, `100us` or raw ticks `123t`.
#pragma once

#include <stdint.h>

#include <string>
#include <string_view>
#include <vector>

#include "sim_board.h"
#include "sim_result.h"

namespace hmc::sim {

enum class Action : uint8_t { kPress, kRelease, kAuto, kEstop, kEstopRelease, kFault, kSend, kStatus };

struct SimCommand {
  Action action = Action::kStatus;
  uint8_t motor = 0;  // press, release, auto: 1 or 2
  uint8_t end = 0;    // press, release, auto: 0 or 1; fault: the STATUS bits
  std::string text;   // send: the line, without its line feed

  bool operator==(const SimCommand& other) const {
    return action == other.action && motor == other.motor && end == other.end && text == other.text;
  }
};

struct ScriptEvent {
  Ticks at = 0;
  SimCommand command;
  uint32_t line = 0;  // in the script file, for messages
};

// One command, without `at`. Surrounding blanks are ignored, except that `send` keeps its text
// verbatim after the one blank that follows the word `send`.
Result<SimCommand> parse_command(std::string_view line);

// A time: digits with an optional fraction and a unit s, ms or us, or whole ticks with t.
// Fractions must come to a whole number of ticks (1/48 µs).
Result<Ticks> parse_time(std::string_view text);

// A whole script, events in time order (lines with equal times keep their file order). The
// error is "LINE: what was wrong" for the first bad line.
Result<std::vector<ScriptEvent>> parse_script(std::string_view text);

// Carries out anything but `status`, at the board's current time.
void apply_command(SimBoard& board, const SimCommand& command);

// The `status` answer: one JSON object, no line feed.
std::string status_json(const SimBoard& board);

}  // namespace hmc::sim
