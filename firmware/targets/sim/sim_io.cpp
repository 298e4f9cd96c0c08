// hmc-sim's endpoints over POSIX descriptors (sim_io.h): standard input and output, TCP
// listeners and their clients, and a pseudo-terminal.
#include "sim_io.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <optional>
#include <utility>

#include "hmc/unique_fd.h"

namespace hmc::sim {
namespace {

constexpr size_t kReadChunk = 4096;

std::string os_error(const std::string& what) { return what + ": " + strerror(errno); }

bool set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL);
  return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

enum class ReadStatus : uint8_t { kData, kNothing, kEnd };

// One read of what poll() said is waiting; appends it to `into`.
ReadStatus read_once(int fd, std::string& into) {
  char buffer[kReadChunk];
  const ssize_t n = read(fd, buffer, sizeof buffer);
  if (n > 0) {
    into.append(buffer, static_cast<size_t>(n));
    return ReadStatus::kData;
  }
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
    return ReadStatus::kNothing;
  }
  return ReadStatus::kEnd;  // end of file, reset, or a pseudo-terminal's closed other side (EIO)
}

enum class Kind : uint8_t { kSocket, kTerminal };

// Writes as much of `pending` as a non-blocking descriptor takes now and removes it. False when
// the peer is gone or has let kMaxPending bytes pile up.
bool write_pending(int fd, std::string& pending, Kind kind) {
  while (!pending.empty()) {
    const ssize_t n = kind == Kind::kSocket ? send(fd, pending.data(), pending.size(), MSG_NOSIGNAL)
                                            : write(fd, pending.data(), pending.size());
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) break;
    if (n < 0) return false;
    pending.erase(0, static_cast<size_t>(n));
  }
  return pending.size() <= kMaxPending;
}

std::string endpoint_text(const sockaddr* address, socklen_t length) {
  char host[NI_MAXHOST];
  char port[NI_MAXSERV];
  if (getnameinfo(address, length, host, sizeof host, port, sizeof port,
                  NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
    return "?";
  }
  const std::string h = host;
  return (h.find(':') != std::string::npos ? "[" + h + "]" : h) + ":" + port;
}

struct Listener {
  UniqueFd fd;
  std::string address;  // tcp://HOST:PORT with the port actually bound
};

Result<Listener> listen_tcp(const std::string& host, uint16_t port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int rc = getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0) {
    return Result<Listener>::fail("cannot resolve '" + host + "': " + gai_strerror(rc));
  }
  std::string error = "no address for '" + host + "'";
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    UniqueFd fd(socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol));
    if (fd.get() < 0) {
      error = os_error("socket");
      continue;
    }
    const int one = 1;
    setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd.get(), a->ai_addr, a->ai_addrlen) != 0 || listen(fd.get(), 8) != 0) {
      error = os_error("cannot listen on " + endpoint_text(a->ai_addr, a->ai_addrlen));
      continue;
    }
    sockaddr_storage bound{};
    socklen_t length = sizeof bound;
    getsockname(fd.get(), reinterpret_cast<sockaddr*>(&bound), &length);
    freeaddrinfo(found);
    return Result<Listener>::ok(Listener{
        std::move(fd), "tcp://" + endpoint_text(reinterpret_cast<sockaddr*>(&bound), length)});
  }
  freeaddrinfo(found);
  return Result<Listener>::fail(error);
}

// A client accepted from `listen_fd`, non-blocking; nullopt when none is waiting any more.
struct Accepted {
  UniqueFd fd;
  std::string from;
};
std::optional<Accepted> accept_client(int listen_fd) {
  sockaddr_storage peer{};
  socklen_t length = sizeof peer;
  UniqueFd fd(accept4(listen_fd, reinterpret_cast<sockaddr*>(&peer), &length,
                SOCK_NONBLOCK | SOCK_CLOEXEC));
  if (fd.get() < 0) return std::nullopt;
  // Bytes go out as the board sends them, a few at a time, as on a serial line: no coalescing.
  const int one = 1;
  setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  std::string from = endpoint_text(reinterpret_cast<sockaddr*>(&peer), length);
  return Accepted{std::move(fd), std::move(from)};
}

void note(Notes notes, const std::string& text) {
  if (notes != nullptr) *notes << "hmc-sim: " << text << '\n' << std::flush;
}

constexpr short kReadable = POLLIN | POLLHUP | POLLERR;

// ---------------------------------------------------------------------------------------

class StdioLink final : public Link {
 public:
  std::string announcement() const override { return {}; }

  void arm(PollSet& poll) override {
    if (!input_ended_) slot_ = poll.add(STDIN_FILENO, POLLIN);
  }

  std::string service(const PollSet& poll) override {
    std::string bytes;
    if (!input_ended_ && (poll.revents(slot_) & kReadable) != 0 &&
        read_once(STDIN_FILENO, bytes) == ReadStatus::kEnd) {
      input_ended_ = true;
    }
    return bytes;
  }

  // Blocking writes: standard output is shared with whoever started us, so it stays as it is;
  // if it was left non-blocking, wait for room.
  void write(std::string_view bytes) override {
    while (!output_closed_ && !bytes.empty()) {
      const ssize_t n = ::write(STDOUT_FILENO, bytes.data(), bytes.size());
      if (n >= 0) {
        bytes.remove_prefix(static_cast<size_t>(n));
      } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
        pollfd out{STDOUT_FILENO, POLLOUT, 0};
        ::poll(&out, 1, -1);
      } else if (errno != EINTR) {
        output_closed_ = true;  // nobody reads the answers: end as at the end of input
        input_ended_ = true;
      }
    }
  }

  bool detached() const override { return input_ended_; }
  bool ends_at_detach() const override { return true; }

 private:
  bool input_ended_ = false;
  bool output_closed_ = false;
  size_t slot_ = 0;
};

// ---------------------------------------------------------------------------------------

class TcpLink final : public Link {
 public:
  TcpLink(Listener listener, Notes notes) : listener_(std::move(listener)), notes_(notes) {}

  std::string announcement() const override { return "listening on " + listener_.address; }

  void arm(PollSet& poll) override {
    if (client_.fd.get() < 0) {
      listen_slot_ = poll.add(listener_.fd.get(), POLLIN);
      return;
    }
    const short out = pending_.empty() ? 0 : POLLOUT;
    client_slot_ =
        poll.add(client_.fd.get(), static_cast<short>((input_ended_ ? 0 : POLLIN) | out));
  }

  std::string service(const PollSet& poll) override {
    std::string bytes;
    if (client_.fd.get() < 0) {
      if ((poll.revents(listen_slot_) & POLLIN) == 0) return bytes;
      if (std::optional<Accepted> accepted = accept_client(listener_.fd.get())) {
        client_ = std::move(*accepted);
        input_ended_ = false;
        note(notes_, "client " + client_.from + " connected");
      }
      return bytes;
    }
    const short events = poll.revents(client_slot_);
    // After the client's end of input only a reset or a full hangup is news.
    if ((events & POLLERR) != 0 || (input_ended_ && (events & POLLHUP) != 0)) {
      drop("disconnected");
      return bytes;
    }
    if (!input_ended_ && (events & (POLLIN | POLLHUP)) != 0 &&
        read_once(client_.fd.get(), bytes) == ReadStatus::kEnd) {
      input_ended_ = true;  // closed once answered (input_taken())
    }
    if ((events & POLLOUT) != 0 && !write_pending(client_.fd.get(), pending_, Kind::kSocket)) {
      drop("too slow or gone");
    }
    return bytes;
  }

  void write(std::string_view bytes) override {
    if (client_.fd.get() < 0) return;
    pending_.append(bytes);
    if (!write_pending(client_.fd.get(), pending_, Kind::kSocket)) drop("too slow or gone");
  }

  void input_taken() override {
    if (client_.fd.get() >= 0 && input_ended_ && pending_.empty()) drop("disconnected");
  }

  bool detached() const override { return client_.fd.get() < 0; }

 private:
  void drop(const char* why) {
    note(notes_, "client " + client_.from + " " + why);
    client_ = Accepted{};
    pending_.clear();
  }

  Listener listener_;
  Notes notes_;
  Accepted client_;
  bool input_ended_ = false;
  std::string pending_;
  size_t listen_slot_ = 0;
  size_t client_slot_ = 0;
};

// ---------------------------------------------------------------------------------------

// While the other side is closed the master reports POLLHUP at every wait, so it leaves the
// wait and is checked again every kRecheckMs instead; what the board sends meanwhile is
// dropped, and what it sent before is flushed as soon as the hangup is seen, so a new opener
// reads neither answers meant for the last one nor the remains of lines it half read (a reader
// may take a byte at a time: flushing once it has opened would cut a line). The link starts
// hung up: until someone opens the other side there is nobody to send to (a board that booted
// before its port was opened is heard from its next line on).
class PtyLink final : public Link {
 public:
  static constexpr int kRecheckMs = 20;

  PtyLink(UniqueFd master, std::string path, Notes notes)
      : master_(std::move(master)), path_(std::move(path)), notes_(notes) {}

  std::string announcement() const override { return "pty " + path_; }

  void arm(PollSet& poll) override {
    if (hung_up_) return;
    const short out = pending_.empty() ? 0 : POLLOUT;
    slot_ = poll.add(master_.get(), static_cast<short>(POLLIN | out));
  }

  std::string service(const PollSet& poll) override {
    std::string bytes;
    if (hung_up_) {
      if (!other_side_closed()) {
        hung_up_ = false;
        note(notes_, path_ + " opened");
      }
      return bytes;
    }
    const short events = poll.revents(slot_);
    if ((events & POLLIN) != 0) read_once(master_.get(), bytes);
    // The hangup the wait saw may be over: the other side can have been opened again (and have
    // written what was just read) since. Only a hangup still there is one.
    if ((events & POLLHUP) != 0 && other_side_closed()) {
      hang_up();
    } else if ((events & POLLOUT) != 0) {
      flush();
    }
    return bytes;
  }

  void write(std::string_view bytes) override {
    if (hung_up_ || other_side_closed()) {
      if (!hung_up_) hang_up();
      return;
    }
    pending_.append(bytes);
    flush();
  }

  bool detached() const override { return hung_up_; }
  int recheck_ms() const override { return hung_up_ ? kRecheckMs : -1; }

 private:
  bool other_side_closed() const {
    pollfd p{master_.get(), POLLIN, 0};
    return ::poll(&p, 1, 0) > 0 && (p.revents & POLLHUP) != 0;
  }

  // The board's output still queued on the other side's input, unread by the one who closed it.
  // Flushing needs a descriptor of that side; its close leaves the hangup as it was.
  void flush_unread_output() {
    UniqueFd other(::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
    if (other.get() >= 0) tcflush(other.get(), TCIFLUSH);
  }

  // An opener that does not read gets nothing more once kMaxPending bytes wait.
  void flush() {
    if (!write_pending(master_.get(), pending_, Kind::kTerminal)) pending_.clear();
  }

  void hang_up() {
    hung_up_ = true;
    pending_.clear();
    flush_unread_output();
    note(notes_, path_ + " closed by the other side; waiting for it to be opened again");
  }

  UniqueFd master_;
  std::string path_;
  Notes notes_;
  bool hung_up_ = true;
  std::string pending_;
  size_t slot_ = 0;
};

}  // namespace

size_t PollSet::add(int fd, short events) {
  fds_.push_back(pollfd{fd, events, 0});
  return fds_.size() - 1;
}

Result<std::unique_ptr<Link>> open_stdio_link() {
  return Result<std::unique_ptr<Link>>::ok(std::make_unique<StdioLink>());
}

Result<std::unique_ptr<Link>> open_tcp_link(const std::string& host, uint16_t port, Notes notes) {
  Result<Listener> listener = listen_tcp(host, port);
  if (!listener) return Result<std::unique_ptr<Link>>::fail(listener.error);
  return Result<std::unique_ptr<Link>>::ok(
      std::make_unique<TcpLink>(std::move(*listener.value), notes));
}

Result<std::unique_ptr<Link>> open_pty_link(Notes notes) {
  using LinkResult = Result<std::unique_ptr<Link>>;
  UniqueFd master(posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (master.get() < 0) return LinkResult::fail(os_error("cannot create a pseudo-terminal"));
  if (grantpt(master.get()) != 0 || unlockpt(master.get()) != 0) {
    return LinkResult::fail(os_error("cannot unlock the pseudo-terminal"));
  }
  char path[128];
  if (ptsname_r(master.get(), path, sizeof path) != 0) {
    return LinkResult::fail(os_error("cannot name the pseudo-terminal"));
  }
  // Raw, set from the master side (it applies to the other side): no echo of what the board
  // sends back into its own input, no line editing, no CR/LF translation.
  termios modes{};
  if (tcgetattr(master.get(), &modes) != 0) return LinkResult::fail(os_error("tcgetattr"));
  cfmakeraw(&modes);
  if (tcsetattr(master.get(), TCSANOW, &modes) != 0) return LinkResult::fail(os_error("tcsetattr"));
  if (!set_nonblocking(master.get())) return LinkResult::fail(os_error("fcntl"));
  // Opened and closed once, the other side reports a hangup until someone opens it; never
  // opened, it reports nothing and the board's first lines would wait there for anyone.
  if (UniqueFd(::open(path, O_RDWR | O_NOCTTY | O_CLOEXEC)).get() < 0) {
    return LinkResult::fail(os_error(std::string("cannot open ") + path));
  }
  return LinkResult::ok(std::make_unique<PtyLink>(std::move(master), path, notes));
}

// ---------------------------------------------------------------------------------------

struct ControlServer::Client {
  Accepted connection;
  LineSplitter lines;
  std::string pending;
  size_t slot = 0;
  bool done = false;
};

Result<std::unique_ptr<ControlServer>> ControlServer::open(const std::string& host, uint16_t port,
                                                           Notes notes) {
  Result<Listener> listener = listen_tcp(host, port);
  if (!listener) return Result<std::unique_ptr<ControlServer>>::fail(listener.error);
  return Result<std::unique_ptr<ControlServer>>::ok(std::make_unique<ControlServer>(
      listener.value->fd.release(), listener.value->address, notes));
}

ControlServer::ControlServer(int listen_fd, std::string address, Notes notes)
    : listen_fd_(listen_fd), address_(std::move(address)), notes_(notes) {}

ControlServer::~ControlServer() { close(listen_fd_); }

std::string ControlServer::address() const { return address_; }

void ControlServer::arm(PollSet& poll) {
  listen_slot_ = poll.add(listen_fd_, POLLIN);
  for (const std::unique_ptr<Client>& client : clients_) {
    const short out = client->pending.empty() ? 0 : POLLOUT;
    client->slot = poll.add(client->connection.fd.get(), static_cast<short>(POLLIN | out));
  }
}

void ControlServer::service(const PollSet& poll, const Handler& handler) {
  for (const std::unique_ptr<Client>& client : clients_) {
    const short events = poll.revents(client->slot);
    const int fd = client->connection.fd.get();
    std::string bytes;
    if ((events & kReadable) != 0 && read_once(fd, bytes) == ReadStatus::kEnd) client->done = true;
    for (const std::string& line : client->lines.feed(bytes)) {
      if (line.find_first_not_of(" \t") == std::string::npos) continue;
      client->pending += handler(line);
      client->pending += '\n';
    }
    if (!write_pending(fd, client->pending, Kind::kSocket)) {
      note(notes_, "control client " + client->connection.from + " too slow or gone");
      client->done = true;
    }
  }
  // A client that closed its sending side gets the answers already queued, as far as they go.
  clients_.erase(std::remove_if(clients_.begin(), clients_.end(),
                                [](const std::unique_ptr<Client>& c) { return c->done; }),
                 clients_.end());
  if ((poll.revents(listen_slot_) & POLLIN) == 0) return;
  while (std::optional<Accepted> accepted = accept_client(listen_fd_)) {
    auto client = std::make_unique<Client>();
    client->connection = std::move(*accepted);
    clients_.push_back(std::move(client));
  }
}

// ---------------------------------------------------------------------------------------

std::vector<std::string> LineSplitter::feed(std::string_view bytes) {
  std::vector<std::string> lines;
  for (const char c : bytes) {
    if (c == '\n') {
      if (!skipping_) {
        if (!partial_.empty() && partial_.back() == '\r') partial_.pop_back();
        lines.push_back(std::move(partial_));
      }
      partial_.clear();
      skipping_ = false;
    } else if (!skipping_) {
      partial_ += c;
      if (partial_.size() == kMaxLine) {
        lines.push_back(std::move(partial_));
        partial_.clear();
        skipping_ = true;
      }
    }
  }
  return lines;
}

}  // namespace hmc::sim
