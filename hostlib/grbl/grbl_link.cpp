// The sender's side of `hmc grbl`: a pseudo-terminal or a TCP listener (grbl_link.h).
#include "hmc/grbl_link.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "hmc/unique_fd.h"

namespace hmc::grbl {
namespace {

constexpr size_t kMaxPending = 1 << 16;  // a sender that stops reading loses output beyond this

Error os_error(const std::string& what) { return Error{what + ": " + std::strerror(errno)}; }

bool nonblocking(int fd) { return fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK) == 0; }

// Reads what is there; false when the other side is gone.
bool read_available(int fd, std::string& into) {
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n > 0) {
      into.append(buffer, static_cast<size_t>(n));
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n < 0 && errno == EINTR) continue;
    return false;  // 0: end of stream; EIO: a pseudo-terminal's other side closed
  }
}

void write_available(int fd, std::string& pending) {
  while (!pending.empty()) {
    const ssize_t n = ::write(fd, pending.data(), pending.size());
    if (n > 0) {
      pending.erase(0, static_cast<size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    return;  // full (EAGAIN) or failing: the poll says what happened
  }
}

class PtySender final : public SenderLink {
 public:
  static constexpr int kRecheckMs = 20;

  PtySender(UniqueFd master, std::string path, std::string link)
      : master_(std::move(master)), path_(std::move(path)), link_(std::move(link)) {}
  ~PtySender() override {
    if (!link_.empty()) ::unlink(link_.c_str());
  }

  std::string address() const override { return path_; }
  bool connected() const override { return !hung_up_; }

  Result<Input> poll(std::chrono::milliseconds timeout) override {
    Input in;
    if (hung_up_) {
      if (other_side_closed()) {
        ::usleep(static_cast<useconds_t>(std::min<long>(timeout.count(), kRecheckMs) * 1000));
        return in;
      }
      hung_up_ = false;
      in.connected = true;
    }
    pollfd p{master_.get(), static_cast<short>(POLLIN | (pending_.empty() ? 0 : POLLOUT)), 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) < 0 && errno != EINTR) return os_error("poll " + path_);
    if ((p.revents & POLLIN) != 0 && !read_available(master_.get(), in.bytes) && other_side_closed()) {
      hang_up(in);
      return in;
    }
    if ((p.revents & POLLHUP) != 0 && other_side_closed()) {
      hang_up(in);
      return in;
    }
    if ((p.revents & POLLOUT) != 0) write_available(master_.get(), pending_);
    return in;
  }

  void write(std::string_view bytes) override {
    if (hung_up_ || bytes.empty()) return;
    if (pending_.size() + bytes.size() <= kMaxPending) pending_.append(bytes);
    write_available(master_.get(), pending_);
  }

 private:
  bool other_side_closed() const {
    pollfd p{master_.get(), POLLIN, 0};
    return ::poll(&p, 1, 0) > 0 && (p.revents & POLLHUP) != 0;
  }

  // What was queued for the sender that left is flushed: the next opener starts clean.
  void hang_up(Input& in) {
    hung_up_ = true;
    in.disconnected = true;
    pending_.clear();
    UniqueFd other(::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
    if (other.get() >= 0) tcflush(other.get(), TCIFLUSH);
  }

  UniqueFd master_;
  std::string path_;
  std::string link_;
  bool hung_up_ = true;
  std::string pending_;
};

class TcpSender final : public SenderLink {
 public:
  TcpSender(UniqueFd listener, std::string address) : listener_(std::move(listener)), address_(std::move(address)) {}

  std::string address() const override { return address_; }
  bool connected() const override { return client_.get() >= 0; }

  Result<Input> poll(std::chrono::milliseconds timeout) override {
    Input in;
    const bool have = client_.get() >= 0;
    pollfd p{have ? client_.get() : listener_.get(),
             static_cast<short>(POLLIN | (have && !pending_.empty() ? POLLOUT : 0)), 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) < 0 && errno != EINTR) return os_error("poll");
    if (!have) {
      if ((p.revents & POLLIN) != 0) {
        UniqueFd client(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK));
        if (client.get() >= 0) {
          const int one = 1;
          setsockopt(client.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
          client_ = std::move(client);
          in.connected = true;
        }
      }
      return in;
    }
    if ((p.revents & (POLLIN | POLLHUP | POLLERR)) != 0 && !read_available(client_.get(), in.bytes)) {
      client_.reset();
      pending_.clear();
      in.disconnected = true;
      return in;
    }
    if ((p.revents & POLLOUT) != 0) write_available(client_.get(), pending_);
    return in;
  }

  void write(std::string_view bytes) override {
    if (client_.get() < 0 || bytes.empty()) return;
    if (pending_.size() + bytes.size() <= kMaxPending) pending_.append(bytes);
    write_available(client_.get(), pending_);
  }

 private:
  UniqueFd listener_;
  UniqueFd client_;
  std::string address_;
  std::string pending_;
};

}  // namespace

Result<std::unique_ptr<SenderLink>> open_pty_sender(const std::string& link) {
  UniqueFd master(posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (master.get() < 0) return os_error("cannot create a pseudo-terminal");
  if (grantpt(master.get()) != 0 || unlockpt(master.get()) != 0) return os_error("cannot unlock the pseudo-terminal");
  char path[128];
  if (ptsname_r(master.get(), path, sizeof path) != 0) return os_error("cannot name the pseudo-terminal");
  termios modes{};
  if (tcgetattr(master.get(), &modes) != 0) return os_error("tcgetattr");
  cfmakeraw(&modes);
  if (tcsetattr(master.get(), TCSANOW, &modes) != 0) return os_error("tcsetattr");
  if (!nonblocking(master.get())) return os_error("fcntl");
  // Opened and closed once, the other side reports a hangup until a sender opens it.
  if (UniqueFd(::open(path, O_RDWR | O_NOCTTY | O_CLOEXEC)).get() < 0) return os_error(std::string("cannot open ") + path);
  if (!link.empty()) {
    ::unlink(link.c_str());
    if (::symlink(path, link.c_str()) != 0) return os_error("cannot make the link " + link);
  }
  return std::unique_ptr<SenderLink>(std::make_unique<PtySender>(std::move(master), path, link));
}

Result<std::unique_ptr<SenderLink>> open_tcp_sender(const std::string& host_port) {
  const size_t colon = host_port.rfind(':');
  if (colon == std::string::npos) return Error{"'" + host_port + "': expected HOST:PORT, e.g. 127.0.0.1:4000"};
  const std::string host = host_port.substr(0, colon);
  char* end = nullptr;
  const long port = std::strtol(host_port.c_str() + colon + 1, &end, 10);
  if (end == host_port.c_str() + colon + 1 || *end != '\0' || port < 0 || port > 65535) {
    return Error{"'" + host_port + "': the port must be a number 0-65535"};
  }
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  if (inet_pton(AF_INET, host.empty() ? "127.0.0.1" : host.c_str(), &address.sin_addr) != 1) {
    return Error{"'" + host + "': not an IPv4 address"};
  }
  UniqueFd listener(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (listener.get() < 0) return os_error("socket");
  const int one = 1;
  setsockopt(listener.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(listener.get(), reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    return os_error("cannot listen on " + host_port);
  }
  if (::listen(listener.get(), 4) != 0) return os_error("listen");
  socklen_t size = sizeof address;
  getsockname(listener.get(), reinterpret_cast<sockaddr*>(&address), &size);
  char text[INET_ADDRSTRLEN];
  inet_ntop(AF_INET, &address.sin_addr, text, sizeof text);
  const std::string name = "tcp://" + std::string(text) + ":" + std::to_string(ntohs(address.sin_port));
  return std::unique_ptr<SenderLink>(std::make_unique<TcpSender>(std::move(listener), name));
}

}  // namespace hmc::grbl
