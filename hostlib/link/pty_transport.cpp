// Pseudo-terminals through termios: the simulator's `hmc-sim --pty` and other programs that
// stand in for a board behind /dev/pts/N. (libserialport cannot open a pseudo-terminal: its
// lookup needs a device in sysfs and it asks for modem lines a pseudo-terminal lacks.)
#include <errno.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "transports.h"

namespace hmc::detail {
namespace {

// termios speed constants for the rates a board link uses; others leave the speed as it is,
// which a pseudo-terminal ignores anyway.
bool speed_constant(uint32_t baud, speed_t& speed) {
  switch (baud) {
    case 9600: speed = B9600; return true;
    case 19200: speed = B19200; return true;
    case 38400: speed = B38400; return true;
    case 57600: speed = B57600; return true;
    case 115200: speed = B115200; return true;
    case 230400: speed = B230400; return true;
    case 460800: speed = B460800; return true;
    case 921600: speed = B921600; return true;
    default: return false;
  }
}

class PtyTransport final : public Transport {
 public:
  PtyTransport(UniqueFd fd, std::string path, const std::string& device, const PortOptions& options)
      : fd_(std::move(fd)),
        path_(std::move(path)),
        description_("pseudo-terminal " + path_ + (device != path_ ? " (" + device + ")" : "")),
        write_timeout_(options.write_timeout) {}

  Status write(std::string_view bytes) override {
    const WriteOutcome outcome = write_fd(fd_.get(), bytes, write_timeout_, FdKind::kTerminal);
    if (outcome.ok(bytes.size())) return Done{};
    if (outcome.timed_out) return Error{write_timeout_message(path_, outcome, bytes.size(), write_timeout_)};
    return Error{lost_message(outcome.error)};
  }

  Result<std::string> read(std::chrono::milliseconds timeout) override {
    ReadOutcome outcome = read_fd(fd_.get(), timeout, FdKind::kTerminal);
    if (outcome.ended) return Error{lost_message(outcome.error)};
    return std::move(outcome.bytes);
  }

  std::string description() const override { return description_; }

 private:
  // EIO (or a hang-up) is how a pseudo-terminal says its other side closed.
  std::string lost_message(int error) const {
    std::string text = "lost the connection to " + path_ + " (the program on its other side closed it";
    if (error != 0 && error != EIO && error != EPIPE) text += std::string(": ") + strerror(error);
    return text + ")";
  }

  UniqueFd fd_;
  std::string path_;
  std::string description_;
  std::chrono::milliseconds write_timeout_;
};

}  // namespace

TransportResult open_pty_port(const std::string& path, const std::string& device, const PortOptions& options) {
  Result<UniqueFd> fd = open_locked(path, path);
  if (!fd) return fd.error();
  termios modes{};
  if (::tcgetattr(fd->get(), &modes) != 0) {
    return Error{"cannot use " + path + " as a terminal: " + strerror(errno)};
  }
  // Raw bytes both ways (no echo, no line editing, no CR/LF translation); no modem lines.
  ::cfmakeraw(&modes);
  modes.c_cflag |= CLOCAL | CREAD;
  if (speed_t speed{}; speed_constant(options.baud, speed)) {
    ::cfsetispeed(&modes, speed);
    ::cfsetospeed(&modes, speed);
  }
  if (::tcsetattr(fd->get(), TCSANOW, &modes) != 0) {
    return Error{"cannot set " + path + " to raw mode: " + strerror(errno)};
  }
  return TransportResult(std::make_unique<PtyTransport>(std::move(fd.value()), path, device, options));
}

}  // namespace hmc::detail
