// The byte transports against real peers made in the test: a TCP listener on 127.0.0.1 and a
// pseudo-terminal pair. Checks bytes both ways, read timeouts and signals, the exclusive lock,
// the link going away, and the message for each way opening a port fails.
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <optional>
#include <system_error>
#include <string>
#include <thread>

#include "hmc/emu_transport.h"
#include "hmc/port_list.h"
#include "hmc/transport.h"
#include "hmc/unique_fd.h"

namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using hmc::UniqueFd;

// A socket bound to 127.0.0.1 on a free port; listening unless told otherwise.
struct Listener {
  UniqueFd fd;
  int port = 0;
  explicit Listener(bool listening = true) : fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    REQUIRE(fd.get() >= 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::bind(fd.get(), reinterpret_cast<sockaddr*>(&address), sizeof address) == 0);
    socklen_t length = sizeof address;
    REQUIRE(::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&address), &length) == 0);
    port = ntohs(address.sin_port);
    if (listening) REQUIRE(::listen(fd.get(), 4) == 0);
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port); }
};

// Reads from `transport` until `want` bytes came or `limit` passed.
std::string read_at_least(hmc::Transport& transport, size_t want, std::chrono::milliseconds limit = 2000ms) {
  std::string got;
  const auto deadline = Clock::now() + limit;
  while (got.size() < want && Clock::now() < deadline) {
    auto bytes = transport.read(100ms);
    REQUIRE(bytes.ok());
    got += *bytes;
  }
  return got;
}

// Reads from a plain descriptor until `want` bytes came or `limit` passed.
std::string read_fd_at_least(int fd, size_t want, std::chrono::milliseconds limit = 2000ms) {
  std::string got;
  const auto deadline = Clock::now() + limit;
  char buffer[256];
  while (got.size() < want && Clock::now() < deadline) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n > 0) {
      got.append(buffer, static_cast<size_t>(n));
    } else {
      std::this_thread::sleep_for(5ms);
    }
  }
  return got;
}

long elapsed_ms(Clock::time_point since) {
  return static_cast<long>(std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - since).count());
}

// A pseudo-terminal pair: we hold the master; the transport opens `slave`.
struct PtyPair {
  UniqueFd master;
  std::string slave;
  PtyPair() : master(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC)) {
    REQUIRE(master.get() >= 0);
    REQUIRE(::grantpt(master.get()) == 0);
    REQUIRE(::unlockpt(master.get()) == 0);
    const char* name = ::ptsname(master.get());
    REQUIRE(name != nullptr);
    slave = name;
    ::fcntl(master.get(), F_SETFL, ::fcntl(master.get(), F_GETFL) | O_NONBLOCK);
  }
};

// A directory of its own under $TMPDIR or /tmp, removed with its contents at the end.
struct TempDir {
  std::string path;
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base != nullptr && *base != '\0' ? base : "/tmp") + "/hmc-transport-XXXXXX";
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

}  // namespace

TEST_CASE("tcp: bytes both ways, read timeout, and the peer closing") {
  Listener listener;
  auto port = hmc::open_port("tcp://" + listener.address());
  REQUIRE(port.ok());
  hmc::Transport& transport = **port;
  CHECK(transport.description() == "tcp " + listener.address());
  CHECK_FALSE(transport.simulated());
  UniqueFd peer(::accept(listener.fd.get(), nullptr, nullptr));
  REQUIRE(peer.get() >= 0);

  const std::string frame = "STX#6#STM#1#1#128#1000#500#94#ETX\n";
  REQUIRE(transport.write(frame).ok());
  CHECK(read_fd_at_least(peer.get(), frame.size()) == frame);

  // Two lines sent together come back from reads as they were sent.
  const std::string lines = "STX#6#STM#3#1#1#11#1000#238#ETX\nSTX#1#OK#ETX\n";
  REQUIRE(::send(peer.get(), lines.data(), lines.size(), 0) == static_cast<ssize_t>(lines.size()));
  CHECK(read_at_least(transport, lines.size()) == lines);

  SECTION("a read with nothing to read returns nothing after about its timeout") {
    const auto start = Clock::now();
    auto bytes = transport.read(150ms);
    const long took = elapsed_ms(start);
    REQUIRE(bytes.ok());
    CHECK(bytes->empty());
    CHECK(took >= 140);
    CHECK(took < 1000);
  }

  SECTION("bytes sent before the peer closed are read first; then the read fails, naming the address") {
    REQUIRE(::send(peer.get(), "last\n", 5, 0) == 5);
    peer.reset();
    CHECK(read_at_least(transport, 5) == "last\n");
    const auto start = Clock::now();
    auto after = transport.read(2000ms);
    REQUIRE_FALSE(after.ok());
    CHECK(after.error().message == "tcp " + listener.address() + " closed the connection");
    CHECK(elapsed_ms(start) < 1000);  // at once, not after the timeout
    CHECK_FALSE(transport.read(10ms).ok());  // and stays failed, without hanging
  }
}

TEST_CASE("tcp: a write the peer never takes fails after the write timeout") {
  Listener listener;
  hmc::PortOptions options;
  options.write_timeout = 200ms;
  auto port = hmc::open_port("tcp://" + listener.address(), options);
  REQUIRE(port.ok());
  UniqueFd peer(::accept(listener.fd.get(), nullptr, nullptr));
  REQUIRE(peer.get() >= 0);
  const std::string flood(64u << 20, 'x');  // more than any socket buffers hold
  const auto start = Clock::now();
  auto written = (*port)->write(flood);
  const long took = elapsed_ms(start);
  REQUIRE_FALSE(written.ok());
  CHECK_THAT(written.error().message, Catch::Contains("writing to tcp " + listener.address() + " timed out after 200 ms"));
  CHECK(took >= 190);
  CHECK(took < 3000);
}

namespace {
void ignore_signal(int) {}
}  // namespace

TEST_CASE("tcp: a signal ends a read's wait without an error") {
  Listener listener;
  auto port = hmc::open_port("tcp://" + listener.address());
  REQUIRE(port.ok());
  UniqueFd peer(::accept(listener.fd.get(), nullptr, nullptr));

  struct sigaction action {};
  struct sigaction previous {};
  action.sa_handler = ignore_signal;  // no SA_RESTART: poll() returns EINTR, as after Ctrl-C
  sigemptyset(&action.sa_mask);
  REQUIRE(::sigaction(SIGUSR1, &action, &previous) == 0);
  const pthread_t reader = ::pthread_self();
  std::thread interrupter([reader] {
    std::this_thread::sleep_for(100ms);
    ::pthread_kill(reader, SIGUSR1);
  });
  const auto start = Clock::now();
  auto bytes = (*port)->read(5000ms);
  const long took = elapsed_ms(start);
  interrupter.join();
  ::sigaction(SIGUSR1, &previous, nullptr);
  REQUIRE(bytes.ok());
  CHECK(bytes->empty());
  CHECK(took < 2000);
}

TEST_CASE("tcp: nothing listening, and malformed addresses") {
  Listener bound_only(false);  // bound but not listening: the connection is refused
  auto refused = hmc::open_port("tcp://" + bound_only.address());
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message == "nothing listens on tcp://" + bound_only.address() +
                                       " (start one with: hmc sim --tcp " + bound_only.address() + ")");

  for (const char* bad : {"tcp://127.0.0.1", "tcp://127.0.0.1:", "tcp://127.0.0.1:0", "tcp://127.0.0.1:65536",
                          "tcp://::1:4000", "tcp://[::1:4000", "tcp://:4000", "tcp://host:40a0"}) {
    INFO(bad);
    auto port = hmc::open_port(bad);
    REQUIRE_FALSE(port.ok());
    CHECK_THAT(port.error().message, Catch::StartsWith(std::string("bad address ") + bad));
  }
}

TEST_CASE("pty: bytes both ways, the lock, and the other side closing") {
  PtyPair pty;
  auto port = hmc::open_port(pty.slave);
  REQUIRE(port.ok());
  hmc::Transport& transport = **port;
  CHECK(transport.description() == "pseudo-terminal " + pty.slave);

  // Raw mode: bytes pass unchanged (no CR added to LF, no echo).
  const std::string frame = "STX#6#STM#1#1#128#1000#500#94#ETX\n";
  REQUIRE(transport.write(frame).ok());
  CHECK(read_fd_at_least(pty.master.get(), frame.size()) == frame);
  const std::string reply = "STX#1#OK#ETX\r\nSTX#2#OK#ETX\n";
  REQUIRE(::write(pty.master.get(), reply.data(), reply.size()) == static_cast<ssize_t>(reply.size()));
  CHECK(read_at_least(transport, reply.size()) == reply);
  CHECK(read_fd_at_least(pty.master.get(), 1, 200ms).empty());  // nothing echoed back

  SECTION("a second opener is refused while the first has it, and let in after") {
    auto second = hmc::open_port(pty.slave);
    REQUIRE_FALSE(second.ok());
    CHECK(second.error().message ==
          "port " + pty.slave + " is in use by another program (close it, or find it with: fuser " + pty.slave + ")");
    port->reset();  // closes the first
    auto third = hmc::open_port(pty.slave);
    CHECK(third.ok());
  }

  SECTION("closing the master fails the next read at once, naming the port") {
    pty.master.reset();
    const auto start = Clock::now();
    auto bytes = transport.read(2000ms);
    REQUIRE_FALSE(bytes.ok());
    CHECK_THAT(bytes.error().message, Catch::StartsWith("lost the connection to " + pty.slave));
    CHECK(elapsed_ms(start) < 1000);
    CHECK_FALSE(transport.write("x").ok());
  }
}

TEST_CASE("pty: a link to a pseudo-terminal is one too, and shares its lock") {
  PtyPair pty;
  TempDir dir;
  const std::string link = dir.path + "/board";
  REQUIRE(::symlink(pty.slave.c_str(), link.c_str()) == 0);
  {
    auto port = hmc::open_port(link);
    REQUIRE(port.ok());
    CHECK((*port)->description() == "pseudo-terminal " + link + " (" + pty.slave + ")");
    REQUIRE((*port)->write("ping\n").ok());
    CHECK(read_fd_at_least(pty.master.get(), 5) == "ping\n");
    auto by_target = hmc::open_port(pty.slave);
    REQUIRE_FALSE(by_target.ok());
    CHECK_THAT(by_target.error().message, Catch::Contains("is in use by another program"));
  }
}

TEST_CASE("opening fails with a message that says what to do") {
  SECTION("a missing device") {
    auto port = hmc::open_port("/dev/ttyHMCNOPE");
    REQUIRE_FALSE(port.ok());
    CHECK(port.error().message == "no such port /dev/ttyHMCNOPE (hmc ports lists the ports this machine has)");
  }
  SECTION("a bare name is looked for in /dev") {
    auto port = hmc::open_port("ttyHMCNOPE");
    REQUIRE_FALSE(port.ok());
    CHECK_THAT(port.error().message, Catch::StartsWith("no such port ttyHMCNOPE"));
  }
  SECTION("no name, or a kind of port there is not") {
    auto empty = hmc::open_port("");
    REQUIRE_FALSE(empty.ok());
    CHECK_THAT(empty.error().message, Catch::StartsWith("no port given"));
    auto unknown = hmc::open_port("udp://127.0.0.1:4000");
    REQUIRE_FALSE(unknown.ok());
    CHECK_THAT(unknown.error().message, Catch::StartsWith("unknown kind of port 'udp://'"));
  }
  SECTION("a file that is not a serial port") {
    TempDir dir;
    const std::string file = dir.path + "/not-a-port";
    REQUIRE(UniqueFd(::open(file.c_str(), O_CREAT | O_WRONLY | O_CLOEXEC, 0600)).get() >= 0);
    auto port = hmc::open_port(file);
    REQUIRE_FALSE(port.ok());
    CHECK_THAT(port.error().message, Catch::StartsWith(file + " is not a serial port"));
  }
  SECTION("a device we may not open") {
    TempDir dir;
    const std::string file = dir.path + "/forbidden";
    REQUIRE(UniqueFd(::open(file.c_str(), O_CREAT | O_WRONLY | O_CLOEXEC, 0600)).get() >= 0);
    REQUIRE(::chmod(file.c_str(), 0) == 0);
    auto port = hmc::open_port(file);
    if (::geteuid() == 0) {
      WARN("running as root, which may open anything: the permission message is not checked");
    } else {
      REQUIRE_FALSE(port.ok());
      CHECK_THAT(port.error().message, Catch::StartsWith("permission denied opening " + file));
      CHECK_THAT(port.error().message, Catch::Contains("sudo usermod -aG dialout $USER"));
      CHECK_THAT(port.error().message, Catch::Contains("udev/70-hmc.rules"));
    }
  }
}

TEST_CASE("the port list") {
  auto ports = hmc::list_ports();
  REQUIRE(ports.ok());  // possibly empty on a machine without serial ports
  for (const hmc::PortInfo& port : *ports) {
    INFO(port.name);
    CHECK(!port.name.empty());
    CHECK((port.kind == "usb" || port.kind == "native" || port.kind == "bluetooth" || port.kind == "virtual"));
    CHECK(port.likely_board == (port.usb_vid == 0x0403 && port.usb_pid == 0x6001));
  }

  hmc::PortInfo board;
  board.name = "/dev/ttyUSB0";
  board.likely_board = true;
  hmc::PortInfo other;
  other.name = "/dev/ttyS0";
  CHECK_FALSE(hmc::find_board_port({}).has_value());
  CHECK_FALSE(hmc::find_board_port({other}).has_value());
  CHECK(hmc::find_board_port({other, board}) == std::optional<std::string>("/dev/ttyUSB0"));
  hmc::PortInfo board2 = board;
  board2.name = "/dev/ttyUSB1";
  CHECK_FALSE(hmc::find_board_port({board, other, board2}).has_value());
}

TEST_CASE("parse_emu_url splits the image and the options") {
  auto plain = hmc::parse_emu_url("emu://");
  REQUIRE(plain.ok());
  CHECK(plain->image.empty());
  CHECK_FALSE(plain->fast);
  auto full = hmc::parse_emu_url("emu:///opt/fw/hmc-firmware.elf?fast&nocrystal&axis=1:0:409600:12800&axis=2:0:1000:500"
                                 "&control=127.0.0.1:4001&trace=out/board.jsonl");
  REQUIRE(full.ok());
  CHECK(full->image == "/opt/fw/hmc-firmware.elf");
  CHECK(full->trace == "out/board.jsonl");
  CHECK(full->fast);
  CHECK(full->no_crystal);
  CHECK(full->axes == std::vector<std::string>{"1:0:409600:12800", "2:0:1000:500"});
  CHECK(full->control == "127.0.0.1:4001");
  auto relative = hmc::parse_emu_url("emu://build/x.elf");
  REQUIRE(relative.ok());
  CHECK(relative->image == "build/x.elf");
  auto unknown = hmc::parse_emu_url("emu://?fast&slow");
  REQUIRE_FALSE(unknown.ok());
  CHECK_THAT(unknown.error().message, Catch::StartsWith("emu://?fast&slow: unknown option 'slow'"));
  auto valued = hmc::parse_emu_url("emu://?fast=1");
  REQUIRE_FALSE(valued.ok());
  CHECK(valued.error().message == "emu://?fast=1: option 'fast' takes no value");
  auto empty = hmc::parse_emu_url("emu://?axis=");
  REQUIRE_FALSE(empty.ok());
  CHECK(empty.error().message == "emu://?axis=: option 'axis' needs a value: axis=M:LOW:HIGH:START");
}

TEST_CASE("an emu:// port whose image or emulator is missing is refused before anything starts") {
  auto image = hmc::open_port("emu:///nonexistent/hmc-firmware.elf");
  REQUIRE_FALSE(image.ok());
  CHECK(image.error().message == "emu:///nonexistent/hmc-firmware.elf: no firmware image '/nonexistent/hmc-firmware.elf' to run");
}
