// Inside libhmc: the three byte transports behind open_port() (transport.cpp), and what they
// share: an owned descriptor, the exclusive open, waiting on a descriptor with poll(), and the
// messages for the failures every kind of port can meet.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hmc/result.h"
#include "hmc/transport.h"
#include "hmc/unique_fd.h"

namespace hmc::detail {

using TransportResult = Result<std::unique_ptr<Transport>>;

// One option of a port URL (sim://, emu://): after '?', options are separated by '&' and each is
// `key` or `key=value`.
struct UrlOption {
  std::string_view key;
  bool has_value = false;
  std::string_view value;  // empty without '='
};
// The options in `query` (what follows '?') in order; empty items are skipped.
std::vector<UrlOption> url_options(std::string_view query);

// `path`: a serial device (symlinks allowed); `name`: what the user called it, for messages.
TransportResult open_serial_port(const std::string& name, const std::string& path, const PortOptions& options);
// `path` is a pseudo-terminal, or a link to one; `device` is the link's target (/dev/pts/N).
TransportResult open_pty_port(const std::string& path, const std::string& device, const PortOptions& options);
// `address` is what follows tcp://: HOST:PORT, or [IPV6]:PORT.
TransportResult open_tcp_port(const std::string& address, const PortOptions& options);

// The messages a person gets, each naming the port and saying what to do.
std::string no_such_port_message(const std::string& name);
std::string permission_message(const std::string& name);
std::string busy_message(const std::string& name);
// An open of `name` failed with `error` (an errno value): one of the messages above, or the
// system's words.
Error open_error(const std::string& name, int error);

// Opens the device `path` read-write, non-blocking, close-on-exec, never as our controlling
// terminal, and takes an exclusive flock() on it, so a second hmc fails here with busy_message.
// The lock lives as long as the descriptor.
Result<UniqueFd> open_locked(const std::string& name, const std::string& path);

enum class FdKind : uint8_t { kTerminal, kSocket };

struct ReadOutcome {
  std::string bytes;
  bool ended = false;  // the link is gone: end of file, hang-up, or `error`
  int error = 0;       // errno when a call failed, 0 for a plain end
};

// Waits at most `timeout` for bytes on a non-blocking `fd`, then takes whatever else is already
// there without waiting. A signal (EINTR) ends the wait with what arrived so far, maybe nothing.
// Bytes that arrived before an end are returned first; the end is seen by the next call.
ReadOutcome read_fd(int fd, std::chrono::milliseconds timeout, FdKind kind);

struct WriteOutcome {
  size_t written = 0;
  bool timed_out = false;
  int error = 0;  // errno when the link failed
  bool ok(size_t wanted) const { return written == wanted; }
};

// Writes all of `bytes` to a non-blocking `fd`, waiting at most `timeout` in all for room.
WriteOutcome write_fd(int fd, std::string_view bytes, std::chrono::milliseconds timeout, FdKind kind);

// The message for a write that did not finish within `timeout`.
std::string write_timeout_message(const std::string& who, const WriteOutcome& outcome, size_t wanted,
                                  std::chrono::milliseconds timeout);

// poll()'s timeout argument for `d`: clamped to [0, INT_MAX] milliseconds.
int poll_ms(std::chrono::milliseconds d);

}  // namespace hmc::detail
