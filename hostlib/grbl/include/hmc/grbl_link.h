// Where a G-code sender reaches `hmc grbl`: a new pseudo-terminal (a serial port to the sender)
// or a TCP listener (a network serial bridge to the sender), one sender at a time, telling when
// one connects and when it goes away.
//
// The pseudo-terminal is raw (no echo, no line editing, no CR/LF translation). It starts hung up;
// a sender opening it is a connection, its last close a disconnection (what was queued for it is
// flushed, so the next opener reads nothing meant for the last one). Over TCP a second client
// waits until the first has gone.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include "hmc/result.h"

namespace hmc::grbl {

class SenderLink {
 public:
  virtual ~SenderLink() = default;
  // "/dev/pts/7", "tcp://127.0.0.1:4000"
  virtual std::string address() const = 0;
  struct Input {
    bool connected = false;     // a sender arrived (before `bytes`)
    std::string bytes;
    bool disconnected = false;  // the sender went away (after `bytes`)
  };
  // Waits at most `timeout` for a sender's bytes or arrival or departure.
  virtual Result<Input> poll(std::chrono::milliseconds timeout) = 0;
  // Writes to the sender; dropped when none is connected.
  virtual void write(std::string_view bytes) = 0;
  virtual bool connected() const = 0;
};

// A new pseudo-terminal; `link` (optional) is a symbolic link made to it and removed at the end.
Result<std::unique_ptr<SenderLink>> open_pty_sender(const std::string& link = "");
// A TCP listener on HOST:PORT (port 0: any free port; address() has the real one).
Result<std::unique_ptr<SenderLink>> open_tcp_sender(const std::string& host_port);

}  // namespace hmc::grbl
