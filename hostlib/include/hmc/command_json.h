// JSON forms of commands, diagnostics and warnings, for `--json` output and test vectors.
#pragma once

#include <nlohmann/json.hpp>

#include "hmc/codec.h"
#include "hmc/command.h"

namespace hmc {

// {"name": "STM", "motor": 1, "dir": 1, ...}: the wire name and every field by its table name.
nlohmann::json command_to_json(const Command& command);
// {"reason": "checksum_mismatch", "code": 8, "token": 8, "offset": 24, "field": "checksum",
//  "expected": 248, "found": 238, "message": "..."}
nlohmann::json diagnostic_to_json(const Diagnostic& diagnostic);
nlohmann::json warnings_to_json(const std::vector<Warning>& warnings);

}  // namespace hmc
