// JSON forms of commands, board frames, diagnostics and warnings, for `--json` output and test
// vectors.
#pragma once

#include <nlohmann/json.hpp>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/command.h"

namespace hmc {

// {"name": "STM", "motor": 1, "dir": 1, ...}: the wire name and every field by its table name.
nlohmann::json command_to_json(const Command& command);
// A board frame, typed: {"name": "STA", "motor": 1, "state": "moving", "position": -1600, ...}.
// Positions are signed; flags are booleans; STA's packed flags are homed, switches, endless and
// microstep; codes are names (state, how, checksum_mode, a NAK's reason with its "code").
nlohmann::json board_frame_to_json(const BoardFrame& frame);
// {"reason": "checksum_mismatch", "code": 8, "token": 8, "offset": 24, "field": "checksum",
//  "expected": 248, "found": 238, "message": "..."}
nlohmann::json diagnostic_to_json(const Diagnostic& diagnostic);
nlohmann::json warnings_to_json(const std::vector<Warning>& warnings);

}  // namespace hmc
