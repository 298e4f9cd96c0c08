// open_port(): picks the transport from the port's name (transport.h), and the pieces the
// descriptor-based transports share (transports.h): the exclusive open, poll()-based reads and
// writes, and the messages for a missing, forbidden or busy port.
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <sstream>

#include "hmc/emu_transport.h"
#include "hmc/sim_transport.h"
#include "hmc/transport.h"
#include "transports.h"

namespace hmc {
namespace detail {

std::vector<UrlOption> url_options(std::string_view query) {
  std::vector<UrlOption> options;
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    if (item.empty()) continue;
    const size_t equals = item.find('=');
    const bool has_value = equals != std::string_view::npos;
    options.push_back({item.substr(0, equals), has_value, has_value ? item.substr(equals + 1) : std::string_view{}});
  }
  return options;
}

std::string no_such_port_message(const std::string& name) {
  return "no such port " + name + " (hmc ports lists the ports this machine has)";
}

std::string permission_message(const std::string& name) {
  return "permission denied opening " + name +
         ": add yourself to the dialout group (sudo usermod -aG dialout $USER, then log in again), "
         "or install the udev rule udev/70-hmc.rules (see docs/ports.md)";
}

std::string busy_message(const std::string& name) {
  return "port " + name + " is in use by another program (close it, or find it with: fuser " + name + ")";
}

Error open_error(const std::string& name, int error) {
  switch (error) {
    case ENOENT:
    case ENOTDIR:
    case ENODEV:
    case ENXIO:  // a device node whose hardware is gone
      return Error{no_such_port_message(name)};
    case EACCES:
    case EPERM:
      return Error{permission_message(name)};
    case EBUSY:  // another program holds it exclusively (TIOCEXCL)
      return Error{busy_message(name)};
    default:
      return Error{"cannot open port " + name + ": " + strerror(error)};
  }
}

Result<UniqueFd> open_locked(const std::string& name, const std::string& path) {
  UniqueFd fd(::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (fd.get() < 0) return open_error(name, errno);
  // flock() rather than TIOCEXCL alone: it also holds against root, and it goes away with the
  // descriptor, even when the process dies. A pseudo-terminal outlives its openers (while its
  // master is open), so a TIOCEXCL left on one would lock out every later opener.
  if (flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) return Error{busy_message(name)};
    return Error{"cannot lock port " + name + ": " + strerror(errno)};
  }
  return fd;
}

int poll_ms(std::chrono::milliseconds d) {
  return static_cast<int>(std::clamp<std::chrono::milliseconds::rep>(d.count(), 0, INT_MAX));
}

namespace {

constexpr size_t kReadChunk = 4096;
// One read() returns at most this much, so a peer that never pauses cannot keep us here.
constexpr size_t kMaxReadBytes = 1 << 20;
constexpr short kHangUp = POLLHUP | POLLERR | POLLNVAL;

bool would_block(int error) { return error == EAGAIN || error == EWOULDBLOCK; }

}  // namespace

ReadOutcome read_fd(int fd, std::chrono::milliseconds timeout, FdKind kind) {
  ReadOutcome out;
  int wait = poll_ms(timeout);
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    const int n = ::poll(&p, 1, wait);
    if (n < 0) {
      if (errno == EINTR) return out;  // the caller checks its Ctrl-C flag
      out.ended = true;
      out.error = errno;
      return out;
    }
    if (n == 0) return out;
    wait = 0;  // from here on take only what is already there
    if ((p.revents & POLLNVAL) != 0) {
      out.ended = true;
      out.error = EBADF;
      return out;
    }
    char buffer[kReadChunk];
    const ssize_t got = kind == FdKind::kSocket ? ::recv(fd, buffer, sizeof buffer, 0)
                                                : ::read(fd, buffer, sizeof buffer);
    if (got > 0) {
      out.bytes.append(buffer, static_cast<size_t>(got));
      if (out.bytes.size() >= kMaxReadBytes) return out;
      continue;
    }
    const int error = got < 0 ? errno : 0;
    if (got < 0 && error == EINTR) return out;
    // Nothing to read although poll() woke us: harmless unless the other side hung up, which
    // would wake every poll() at once and spin.
    if (got < 0 && would_block(error) && (p.revents & kHangUp) == 0) return out;
    // End of file, a pseudo-terminal whose other side closed (EIO), a reset, an unplugged
    // device: the link is gone. What came before it is delivered first.
    if (!out.bytes.empty()) return out;
    out.ended = true;
    out.error = would_block(error) ? 0 : error;
    return out;
  }
}

WriteOutcome write_fd(int fd, std::string_view bytes, std::chrono::milliseconds timeout, FdKind kind) {
  WriteOutcome out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (out.written < bytes.size()) {
    const char* data = bytes.data() + out.written;
    const size_t size = bytes.size() - out.written;
    // MSG_NOSIGNAL: a closed socket is an error to report, not a SIGPIPE that ends the program.
    const ssize_t n = kind == FdKind::kSocket ? ::send(fd, data, size, MSG_NOSIGNAL) : ::write(fd, data, size);
    if (n > 0) {
      out.written += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EINTR && !would_block(errno)) {
      out.error = errno;
      return out;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      out.timed_out = true;
      return out;
    }
    pollfd p{fd, POLLOUT, 0};
    const int ready = ::poll(&p, 1, poll_ms(left));
    if (ready < 0 && errno != EINTR) {
      out.error = errno;
      return out;
    }
    if (ready > 0 && (p.revents & POLLOUT) == 0 && (p.revents & kHangUp) != 0) {
      out.error = (p.revents & POLLNVAL) != 0 ? EBADF : EPIPE;  // gone; writing again would spin
      return out;
    }
  }
  return out;
}

std::string write_timeout_message(const std::string& who, const WriteOutcome& outcome, size_t wanted,
                                  std::chrono::milliseconds timeout) {
  std::ostringstream text;
  text << "writing to " << who << " timed out after " << timeout.count() << " ms with " << outcome.written
       << " of " << wanted << " bytes sent (the other side is not reading: is the board running?)";
  return text.str();
}

namespace {

bool starts_with(std::string_view s, std::string_view prefix) { return s.substr(0, prefix.size()) == prefix; }

// Unix98 pseudo-terminal slaves: character majors 136-143 (the kernel's devices.txt), normally
// seen as /dev/pts/N. /dev/pts/ptmx is the multiplexer, not a terminal.
bool is_pseudo_terminal(const std::string& resolved) {
  struct stat st {};
  if (::stat(resolved.c_str(), &st) != 0 || !S_ISCHR(st.st_mode)) return false;
  const unsigned major_number = major(st.st_rdev);
  if (major_number >= 136 && major_number <= 143) return true;
  return starts_with(resolved, "/dev/pts/") && resolved != "/dev/pts/ptmx";
}

std::string resolve(const std::string& path) {
  char* resolved = ::realpath(path.c_str(), nullptr);
  if (resolved == nullptr) return path;
  std::string result = resolved;
  ::free(resolved);
  return result;
}

}  // namespace
}  // namespace detail

Result<std::unique_ptr<Transport>> open_port(const std::string& name, const PortOptions& options) {
  using detail::starts_with;
  if (name.empty()) {
    return Error{"no port given (a device such as /dev/ttyUSB0, tcp://HOST:PORT or sim://; "
                 "hmc ports lists the ports this machine has)"};
  }
  if (starts_with(name, "sim://")) return open_sim_port(name, options);
  if (starts_with(name, "emu://")) return open_emu_port(name, options);
  if (starts_with(name, "tcp://")) return detail::open_tcp_port(name.substr(6), options);
  if (const size_t scheme = name.find("://"); scheme != std::string::npos) {
    return Error{"unknown kind of port '" + name.substr(0, scheme + 3) + "' in " + name +
                 " (use a device such as /dev/ttyUSB0, tcp://HOST:PORT, sim:// or emu://)"};
  }
  // A bare device name (ttyUSB0) means the device in /dev.
  std::string path = name;
  if (path.find('/') == std::string::npos && ::access(("/dev/" + path).c_str(), F_OK) == 0) path = "/dev/" + path;

  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return detail::open_error(path, errno);
  const std::string resolved = detail::resolve(path);
  if (detail::is_pseudo_terminal(resolved)) return detail::open_pty_port(path, resolved, options);
  return detail::open_serial_port(path, resolved, options);
}

}  // namespace hmc
