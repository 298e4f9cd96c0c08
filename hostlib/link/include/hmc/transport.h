// Transport: one byte stream to a board, whatever carries it, and open_port(), which picks the
// transport from the port's name.
//
// Names (docs/ports.md):
//   sim://[NAME][?OPTION&...]  the simulated board, in this process (sim_transport.h)
//   emu://[IMAGE][?OPTION&...] the firmware image on hmc-emu, a child process (emu_transport.h)
//   tcp://HOST:PORT            a network serial bridge, or `hmc-sim --tcp`
//   /dev/pts/N, or a link to one   a pseudo-terminal, through termios (`hmc-sim --pty`)
//   anything else              a serial port through libserialport (/dev/ttyUSB0; ttyUSB0 means
//                              /dev/ttyUSB0)
//
// Serial ports and pseudo-terminals are opened 8N1 without flow control and locked exclusively
// (flock), so two programs never share a board. Every failure is an Error whose message names
// the port and says what to do (missing port, permission denied and the dialout group, port
// busy, board unplugged).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "hmc/result.h"

namespace hmc {

class Transport {
 public:
  virtual ~Transport() = default;
  // Writes every byte, waiting at most the port's timeout for the link to take them.
  virtual Status write(std::string_view bytes) = 0;
  // Waits at most `timeout` for bytes and returns those that arrived: empty when none did.
  // An error means the link is gone (unplugged, closed by the other side).
  virtual Result<std::string> read(std::chrono::milliseconds timeout) = 0;
  // Which board this is, for people: "serial /dev/ttyUSB0 at 115200 baud",
  // "tcp 127.0.0.1:4000", "simulated board sim://default".
  virtual std::string description() const = 0;
  // True for a board that exists only while this program has it open (sim://, emu://): nothing
  // of it runs on when the program dies.
  virtual bool simulated() const { return false; }
  // True when the transport itself knows its board runs the seed firmware, which answers
  // nothing (the simulated board's ?seed); a real port never knows.
  virtual bool seed_firmware() const { return false; }
};

struct PortOptions {
  uint32_t baud = 115200;
  std::chrono::milliseconds write_timeout{1000};
};

inline constexpr uint32_t kDefaultBaud = 115200;

// Opens the port `name` names (see the top of this file).
Result<std::unique_ptr<Transport>> open_port(const std::string& name, const PortOptions& options = {});

}  // namespace hmc
