// tcp://HOST:PORT: a board behind a network serial bridge, or the simulator's TCP listener. The
// connection is made within kConnectTimeout, with Nagle's delay off so each frame leaves at once.
#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <optional>

#include "transports.h"

namespace hmc::detail {
namespace {

constexpr std::chrono::milliseconds kConnectTimeout{3000};
// What a person can run to get a listener: the simulated board (`hmc sim`, cli/sim_command.cpp).
constexpr const char* kStartListener = "hmc sim --tcp ";

struct HostPort {
  std::string host;  // without the brackets of an IPv6 address
  std::string port;
};

std::optional<HostPort> split_address(const std::string& address) {
  std::string host;
  std::string rest;
  if (!address.empty() && address.front() == '[') {
    const size_t close = address.find(']');
    if (close == std::string::npos) return std::nullopt;
    host = address.substr(1, close - 1);
    rest = address.substr(close + 1);
  } else {
    const size_t colon = address.rfind(':');
    if (colon == std::string::npos) return std::nullopt;
    host = address.substr(0, colon);
    rest = address.substr(colon);
    if (host.find(':') != std::string::npos) return std::nullopt;  // IPv6 needs its brackets
  }
  if (host.empty() || rest.size() < 2 || rest.front() != ':') return std::nullopt;
  const std::string port = rest.substr(1);
  if (port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  unsigned number = 0;
  for (const char c : port) number = number * 10 + static_cast<unsigned>(c - '0');
  if (number == 0 || number > 65535) return std::nullopt;
  return HostPort{host, port};
}

class TcpTransport final : public Transport {
 public:
  TcpTransport(UniqueFd fd, std::string address, const PortOptions& options)
      : fd_(std::move(fd)), address_(std::move(address)), write_timeout_(options.write_timeout) {}

  Status write(std::string_view bytes) override {
    const WriteOutcome outcome = write_fd(fd_.get(), bytes, write_timeout_, FdKind::kSocket);
    if (outcome.ok(bytes.size())) return Done{};
    if (outcome.timed_out) return Error{write_timeout_message("tcp " + address_, outcome, bytes.size(), write_timeout_)};
    return Error{closed_message(outcome.error)};
  }

  Result<std::string> read(std::chrono::milliseconds timeout) override {
    ReadOutcome outcome = read_fd(fd_.get(), timeout, FdKind::kSocket);
    if (outcome.ended) return Error{closed_message(outcome.error)};
    return std::move(outcome.bytes);
  }

  std::string description() const override { return "tcp " + address_; }

 private:
  std::string closed_message(int error) const {
    std::string text = "tcp " + address_ + " closed the connection";
    if (error != 0 && error != EPIPE) text += std::string(" (") + strerror(error) + ")";
    return text;
  }

  UniqueFd fd_;
  std::string address_;
  std::chrono::milliseconds write_timeout_;
};

// One attempt at one resolved address; `error` says why it failed.
UniqueFd connect_one(const addrinfo& a, std::chrono::steady_clock::time_point deadline, int& error) {
  UniqueFd fd(::socket(a.ai_family, a.ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a.ai_protocol));
  if (fd.get() < 0) {
    error = errno;
    return UniqueFd();
  }
  if (::connect(fd.get(), a.ai_addr, a.ai_addrlen) != 0) {
    if (errno != EINPROGRESS) {
      error = errno;
      return UniqueFd();
    }
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pollfd p{fd.get(), POLLOUT, 0};
      const int ready = left.count() > 0 ? ::poll(&p, 1, poll_ms(left)) : 0;
      if (ready < 0 && errno == EINTR) continue;
      if (ready < 0) {
        error = errno;
        return UniqueFd();
      }
      if (ready == 0) {
        error = ETIMEDOUT;
        return UniqueFd();
      }
      break;
    }
    int result = 0;
    socklen_t length = sizeof result;
    if (::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &result, &length) != 0) result = errno;
    if (result != 0) {
      error = result;
      return UniqueFd();
    }
  }
  const int one = 1;
  ::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

}  // namespace

TransportResult open_tcp_port(const std::string& address, const PortOptions& options) {
  const std::string url = "tcp://" + address;
  const std::optional<HostPort> parts = split_address(address);
  if (!parts) {
    return Error{"bad address " + url + " (write tcp://HOST:PORT with a port from 1 to 65535, "
                 "e.g. tcp://127.0.0.1:4000, or tcp://[::1]:4000 for IPv6)"};
  }

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(parts->host.c_str(), parts->port.c_str(), &hints, &found); rc != 0) {
    if (rc == EAI_NONAME || rc == EAI_AGAIN || rc == EAI_FAIL || rc == EAI_NODATA) {
      return Error{"unknown host '" + parts->host + "' in " + url + " (check the name, or give an IP address)"};
    }
    return Error{"cannot look up '" + parts->host + "' in " + url + ": " + gai_strerror(rc)};
  }

  // Every address the name has, within one overall timeout; the last failure is the one told.
  const auto deadline = std::chrono::steady_clock::now() + kConnectTimeout;
  int error = 0;
  UniqueFd fd;
  for (const addrinfo* a = found; a != nullptr && fd.get() < 0; a = a->ai_next) {
    fd = connect_one(*a, deadline, error);
  }
  ::freeaddrinfo(found);
  if (fd.get() >= 0) return TransportResult(std::make_unique<TcpTransport>(std::move(fd), address, options));

  switch (error) {
    case ECONNREFUSED:
      return Error{"nothing listens on " + url + " (start one with: " + kStartListener + address + ")"};
    case ETIMEDOUT:
      return Error{"no answer from " + url + " within " + std::to_string(kConnectTimeout.count() / 1000) +
                   " s (is the address right, and the bridge switched on and on this network?)"};
    case ENETUNREACH:
    case EHOSTUNREACH:
      return Error{"cannot reach " + url + ": " + strerror(error) + " (check the address and this machine's network)"};
    default:
      return Error{"cannot connect to " + url + ": " + strerror(error)};
  }
}

}  // namespace hmc::detail
