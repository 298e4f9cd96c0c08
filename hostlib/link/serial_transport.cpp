// Real serial ports (/dev/ttyUSB0, /dev/ttyACM0, /dev/ttyS0) through libserialport: 8N1, no flow
// control, locked exclusively. Reads wait with poll() on the port's descriptor, so the caller's
// timeout, a signal and an unplugged device are all seen at once.
#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <libserialport.h>

#include <algorithm>
#include <climits>

#include "transports.h"

namespace hmc::detail {
namespace {

// What libserialport said last, for messages.
std::string last_serial_error() {
  char* message = sp_last_error_message();
  std::string text = message != nullptr ? message : "unknown error";
  sp_free_error_message(message);
  return text;
}

std::string not_a_port_message(const std::string& name) {
  return name + " is not a serial port (hmc ports lists the ports this machine has)";
}

// The errors a port gives once its device is gone (USB unplugged, the board reset its bridge).
bool device_gone(int error) { return error == EIO || error == ENODEV || error == ENXIO || error == EPIPE; }

class SerialTransport final : public Transport {
 public:
  SerialTransport(std::string name, sp_port* port, UniqueFd lock, const PortOptions& options)
      : name_(std::move(name)), port_(port), lock_(std::move(lock)), options_(options) {
    sp_get_port_handle(port_, &fd_);
  }

  ~SerialTransport() override {
    ::ioctl(fd_, TIOCNXCL);
    sp_close(port_);
    sp_free_port(port_);
  }

  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  Status write(std::string_view bytes) override {
    if (bytes.empty()) return Done{};
    // libserialport reads a timeout of 0 as "wait forever".
    const auto timeout_ms = static_cast<unsigned>(std::clamp<std::chrono::milliseconds::rep>(
        options_.write_timeout.count(), 1, static_cast<std::chrono::milliseconds::rep>(UINT_MAX)));
    const sp_return written = sp_blocking_write(port_, bytes.data(), bytes.size(), timeout_ms);
    if (written < 0) {
      const int error = sp_last_error_code();
      if (device_gone(error)) return Error{lost_message()};
      return Error{"cannot write to " + name_ + ": " + last_serial_error()};
    }
    if (static_cast<size_t>(written) < bytes.size()) {
      WriteOutcome outcome;
      outcome.written = static_cast<size_t>(written);
      outcome.timed_out = true;
      return Error{write_timeout_message(name_, outcome, bytes.size(), options_.write_timeout)};
    }
    return Done{};
  }

  Result<std::string> read(std::chrono::milliseconds timeout) override {
    ReadOutcome outcome = read_fd(fd_, timeout, FdKind::kTerminal);
    if (outcome.ended) {
      if (outcome.error == 0 || device_gone(outcome.error)) return Error{lost_message()};
      return Error{"cannot read from " + name_ + ": " + strerror(outcome.error)};
    }
    return std::move(outcome.bytes);
  }

  std::string description() const override {
    return "serial " + name_ + " at " + std::to_string(options_.baud) + " baud";
  }

 private:
  std::string lost_message() const { return "lost the connection to " + name_ + " (unplugged?)"; }

  std::string name_;
  sp_port* port_;
  UniqueFd lock_;  // holds the flock() for as long as the port is open
  PortOptions options_;
  int fd_ = -1;
};

// Frees a port libserialport gave us unless it is handed on.
struct PortOwner {
  sp_port* port = nullptr;
  bool opened = false;
  ~PortOwner() {
    if (port == nullptr) return;
    if (opened) sp_close(port);
    sp_free_port(port);
  }
  sp_port* release() { return std::exchange(port, nullptr); }
};

}  // namespace

TransportResult open_serial_port(const std::string& name, const std::string& path, const PortOptions& options) {
  // Our own descriptor first: it tells a missing, forbidden or busy port apart, and the lock is
  // taken before libserialport changes the settings of a port another program may be using.
  Result<UniqueFd> lock = open_locked(name, path);
  if (!lock) return lock.error();

  // libserialport looks the device up in sysfs by its /dev name, so it gets the link's target.
  // Its lookup fails for anything that is not a serial device it knows (its own message is
  // just "No such file or directory", which would mislead here).
  PortOwner owner;
  if (sp_get_port_by_name(path.c_str(), &owner.port) != SP_OK) return Error{not_a_port_message(name)};
  if (sp_open(owner.port, SP_MODE_READ_WRITE) != SP_OK) {
    const int error = sp_last_error_code();
    if (error == ENOTTY || error == EINVAL) return Error{not_a_port_message(name)};  // no serial settings
    if (error != 0) return open_error(name, error);
    return Error{"cannot open port " + name + ": " + last_serial_error()};
  }
  owner.opened = true;

  if (sp_set_baudrate(owner.port, static_cast<int>(options.baud)) != SP_OK ||
      sp_set_bits(owner.port, 8) != SP_OK || sp_set_parity(owner.port, SP_PARITY_NONE) != SP_OK ||
      sp_set_stopbits(owner.port, 1) != SP_OK || sp_set_flowcontrol(owner.port, SP_FLOWCONTROL_NONE) != SP_OK) {
    return Error{"cannot set " + name + " to " + std::to_string(options.baud) +
                 " baud, 8 data bits, no parity, 1 stop bit: " + last_serial_error()};
  }

  int fd = -1;
  sp_get_port_handle(owner.port, &fd);
  // Non-blocking for read_fd(), kept from programs we start (flashing tools), and exclusive at
  // the terminal layer too: other programs that open the port without flock() are refused.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  ::fcntl(fd, F_SETFD, FD_CLOEXEC);
  ::ioctl(fd, TIOCEXCL);

  owner.opened = false;
  return TransportResult(std::make_unique<SerialTransport>(name, owner.release(), std::move(lock.value()), options));
}

}  // namespace hmc::detail
