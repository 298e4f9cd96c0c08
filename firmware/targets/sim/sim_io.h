// The endpoints hmc-sim serves, all driven by one poll() loop: the board's link (standard
// input and output, a TCP listener, or a pseudo-terminal) and the control channel (a TCP
// listener taking one injected-event command per line).
//
// Every endpoint adds its descriptors to a PollSet before the wait and handles what the wait
// found afterwards. Writes never block the loop on a socket or a pseudo-terminal: what the
// peer has not taken yet waits in a buffer; a peer that lets more than kMaxPending bytes pile up
// is dropped. Standard output is written with blocking writes, as a pipe expects.
#pragma once

#include <poll.h>
#include <stddef.h>
#include <stdint.h>

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "sim_result.h"

namespace hmc::sim {

inline constexpr size_t kMaxPending = size_t{1} << 20;

// The descriptors of one wait.
class PollSet {
 public:
  void clear() { fds_.clear(); }
  // Returns the slot to ask revents() about after the wait.
  size_t add(int fd, short events);
  short revents(size_t slot) const { return fds_[slot].revents; }
  std::vector<pollfd>& fds() { return fds_; }

 private:
  std::vector<pollfd> fds_;
};

// Where notes about clients (connected, gone) go; null to keep quiet.
using Notes = std::ostream*;

// The board's serial line, as the host sees it.
class Link {
 public:
  virtual ~Link() = default;
  // What to print once the link is ready: "listening on tcp://127.0.0.1:4000",
  // "pty /dev/pts/3"; empty for standard input and output.
  virtual std::string announcement() const = 0;
  // Adds its descriptors to the next wait.
  virtual void arm(PollSet& poll) = 0;
  // After the wait: accepts, reads, writes what waits, notices hangups. Returns the bytes read.
  virtual std::string service(const PollSet& poll) = 0;
  // Bytes for the host; dropped while nobody is on the other side.
  virtual void write(std::string_view bytes) = 0;
  // Nobody is on the other side: standard input ended, no TCP client, or the pseudo-terminal's
  // other side was closed.
  virtual bool detached() const = 0;
  // Standard input: its end ends the session.
  virtual bool ends_at_detach() const { return false; }
  // Called whenever the board has taken in every byte read so far: a TCP client that has
  // closed its sending side is disconnected once its answers are out.
  virtual void input_taken() {}
  // The longest wait, in ms, this link needs (the pseudo-terminal polls for a reopen), or -1.
  virtual int recheck_ms() const { return -1; }
};

Result<std::unique_ptr<Link>> open_stdio_link();
// Listens on host:port (port 0: any free port); one client at a time, the next waits.
Result<std::unique_ptr<Link>> open_tcp_link(const std::string& host, uint16_t port, Notes notes);
// A new pseudo-terminal in raw mode; its other side may be opened and closed any number of times.
Result<std::unique_ptr<Link>> open_pty_link(Notes notes);

// The control channel: a TCP listener; any number of clients, each line a command.
class ControlServer {
 public:
  // Answers one line (without its end); the answer is sent back with a line feed.
  using Handler = std::function<std::string(std::string_view line)>;

  static Result<std::unique_ptr<ControlServer>> open(const std::string& host, uint16_t port,
                                                     Notes notes);
  ControlServer(int listen_fd, std::string address, Notes notes);  // takes the descriptor
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  std::string address() const;
  void arm(PollSet& poll);
  // After the wait: accepts clients and answers every complete non-blank line, in order.
  void service(const PollSet& poll, const Handler& handler);

 private:
  struct Client;

  int listen_fd_;
  std::string address_;
  Notes notes_;
  size_t listen_slot_ = 0;
  std::vector<std::unique_ptr<Client>> clients_;
};

// Splits a byte stream into lines: ended by LF, a CR before it dropped. A line longer than
// kMaxLine is cut there and the rest of it skipped.
class LineSplitter {
 public:
  static constexpr size_t kMaxLine = 4096;
  // Adds bytes; returns the lines they completed.
  std::vector<std::string> feed(std::string_view bytes);

 private:
  std::string partial_;
  bool skipping_ = false;
};

}  // namespace hmc::sim
