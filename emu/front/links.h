// The command UART's link for hmc-emu, chosen as hmc-sim chooses its own (docs/sim.md, "The
// link"): standard input/output, a TCP listener (--tcp) or a pseudo-terminal (--pty). The links
// themselves are hmc-sim's (sim_io.h), shared, not copied.
#pragma once

#include <memory>
#include <string>

#include "sim_io.h"

namespace hmc::emu {

// `tcp`: HOST:PORT (already checked by the option), empty for none.
sim::Result<std::unique_ptr<sim::Link>> open_link(bool pty, const std::string& tcp, sim::Notes notes);

}  // namespace hmc::emu
