// sim://: the simulated board (the real firmware core on a virtual clock) as a transport in this
// process, so every host command can run without the hardware (docs/sim.md "The simulated board
// in every command: sim://").
//
// The board stays "powered" between commands: every write is appended to a journal, which the
// next opener of the same sim://NAME replays (exactly: the board is deterministic) before going
// on from where the last command left it. Its clock runs only while a command is connected.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "hmc/result.h"
#include "hmc/transport.h"

namespace hmc {

struct SimPortOptions {
  std::string name = "default";  // sim://NAME
  bool fast = false;    // ?fast: virtual time runs as fast as the host reads; else it follows the wall clock
  bool seed = false;    // ?seed: the seed firmware: legacy rules and no replies
  bool legacy = false;  // ?legacy: legacy rules with replies
  bool fresh = false;   // ?fresh: forget the saved state: a board just powered up
  bool keep = true;     // ?nosave (keep=false): nothing is saved when the port closes
  std::string trace;    // ?trace=PATH: append the board's JSON-lines trace to PATH
};

// "sim://", "sim://bench", "sim://bench?fast&seed&trace=/tmp/t.jsonl". NAME is letters, digits,
// '.', '_' and '-' (it names a file), empty for "default". Errors name the unknown option.
Result<SimPortOptions> parse_sim_url(std::string_view url);

// The directory holding the boards' journals: $HMC_SIM_STATE, else $XDG_STATE_HOME/hmc, else
// ~/.local/state/hmc. Not created here.
Result<std::string> sim_state_directory();

// Opens the simulated board `url` names (parse_sim_url). options.baud paces the bytes both ways,
// as on the wire. Fails when the URL is bad, the state directory cannot be created or written,
// or another program has the same board open; a journal that cannot be replayed is set aside
// and the board starts fresh, which description() then says.
Result<std::unique_ptr<Transport>> open_sim_port(std::string_view url, const PortOptions& options);

}  // namespace hmc
