// hmc-emu's link (links.h).
#include "links.h"

#include "sim_options.h"

namespace hmc::emu {

sim::Result<std::unique_ptr<sim::Link>> open_link(bool pty, const std::string& tcp, sim::Notes notes) {
  if (pty) return sim::open_pty_link(notes);
  if (!tcp.empty()) {
    const sim::HostPort at = *sim::parse_host_port(tcp).value;
    return sim::open_tcp_link(at.host, at.port, notes);
  }
  return sim::open_stdio_link();
}

}  // namespace hmc::emu
