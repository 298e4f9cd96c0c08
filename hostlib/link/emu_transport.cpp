// emu://: hmc-emu as a child process on a pseudo-terminal (hmc/emu_transport.h). This process
// holds the pseudo-terminal's master side; hmc-emu gets its other side as standard input and
// output (its stdio link), so the command UART's bytes flow through the pair, raw, as through
// `hmc-emu --pty`. The child is in a process group of its own, so a Ctrl-C reaches only hmc,
// which stops the motors before it lets go.
#include "hmc/emu_transport.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>
#include <variant>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/line_splitter.h"
#include "transports.h"

namespace hmc {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The image's power-up self-test (each stepper half a turn out and back at 250 µs a step:
// docs/protocol.md, "Boot") is over by then, so the board is idle when the host's first byte
// arrives, as a board that has been on for a while is. Virtual time: hmc-emu holds the bytes.
constexpr const char* kHoldInputSeconds = "1.0";
// hmc-emu boots and runs the self-test in well under this even under the sanitizers.
constexpr auto kStartTimeout = std::chrono::seconds(60);
constexpr auto kEndTimeout = std::chrono::seconds(2);
constexpr const char* kFirmwareInBuildTree = "build/firmware/firmware/targets/samd21/hmc-firmware.elf";
// The hmc-firmware package's image: raw flash bytes at 0x2000, which hmc-emu runs as they are.
constexpr const char* kFirmwareInstalled = "../share/hmc/firmware/hmc-firmware.bin";

std::string env(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}

bool executable(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && ::access(path.c_str(), X_OK) == 0;
}

bool readable_file(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && ::access(path.c_str(), R_OK) == 0;
}

// The directory of this program (not of a script running it): where an installed or built
// hmc-emu sits beside it.
fs::path own_directory() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

Result<std::string> find_emulator() {
  if (const std::string given = env("HMC_EMU"); !given.empty()) {
    if (!executable(given)) return Error{"HMC_EMU is '" + given + "', which is not an executable program"};
    return given;
  }
  const fs::path here = own_directory();
  if (!here.empty()) {
    for (const fs::path& candidate : {here / "hmc-emu", here / ".." / "emu" / "hmc-emu"}) {
      if (executable(candidate)) return candidate.lexically_normal().string();
    }
  }
  const std::string path = env("PATH");
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find(':', start), path.size());
    const fs::path dir = path.substr(start, end - start);
    if (!dir.empty() && executable(dir / "hmc-emu")) return (dir / "hmc-emu").string();
    start = end + 1;
  }
  return Error{"emu://: hmc-emu was not found (beside this program, in its build tree, or on PATH): install "
               "the hmc-emu package, build it (cmake --build --preset default --target hmc_emu), or set HMC_EMU "
               "to its path"};
}

Result<std::string> find_image(const std::string& given, const std::string& emulator) {
  if (!given.empty()) {
    if (!readable_file(given)) return Error{"emu://" + given + ": no firmware image '" + given + "' to run"};
    return given;
  }
  if (const std::string from_env = env("HMC_EMU_FIRMWARE"); !from_env.empty()) {
    if (!readable_file(from_env)) return Error{"HMC_EMU_FIRMWARE is '" + from_env + "', which is not a readable file"};
    return from_env;
  }
  std::vector<fs::path> looked;
  // A build tree inside the checkout: the firmware preset's image in the checkout above.
  for (fs::path dir = own_directory(); !dir.empty(); dir = dir.parent_path()) {
    if (readable_file(dir / kFirmwareInBuildTree)) return (dir / kFirmwareInBuildTree).string();
    if (dir == dir.parent_path()) break;
  }
  for (const fs::path& bindir : {own_directory(), fs::path(emulator).parent_path()}) {
    if (bindir.empty()) continue;
    const fs::path installed = (bindir / kFirmwareInstalled).lexically_normal();
    if (readable_file(installed)) return installed.string();
    looked.push_back(installed);
  }
  std::string where;
  for (const fs::path& p : looked) where += (where.empty() ? "" : ", ") + p.string();
  return Error{"emu://: no firmware image given and none found (not in a build tree with the firmware preset built, "
               "not installed" + (where.empty() ? std::string() : " in " + where) +
               "): name it, emu:///path/to/hmc-firmware.elf, set HMC_EMU_FIRMWARE, or install the hmc-firmware package"};
}

std::string describe_end(int status) {
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
}

class EmuTransport final : public Transport {
 public:
  EmuTransport(UniqueFd master, pid_t child, std::string url, std::string description, const PortOptions& options)
      : master_(std::move(master)),
        child_(child),
        url_(std::move(url)),
        description_(std::move(description)),
        write_timeout_(options.write_timeout) {}

  ~EmuTransport() override { end_child(); }

  EmuTransport(const EmuTransport&) = delete;
  EmuTransport& operator=(const EmuTransport&) = delete;

  Status write(std::string_view bytes) override {
    const detail::WriteOutcome outcome =
        detail::write_fd(master_.get(), bytes, write_timeout_, detail::FdKind::kTerminal);
    if (outcome.ok(bytes.size())) return Done{};
    if (outcome.timed_out) return Error{detail::write_timeout_message(url_, outcome, bytes.size(), write_timeout_)};
    return Error{lost_message()};
  }

  Result<std::string> read(std::chrono::milliseconds timeout) override {
    detail::ReadOutcome outcome = detail::read_fd(master_.get(), timeout, detail::FdKind::kTerminal);
    if (outcome.ended) return Error{lost_message()};
    return std::move(outcome.bytes);
  }

  std::string description() const override { return description_; }

  // The emulated board exists only while this process has it open: nothing of it runs on when
  // hmc dies, so (as for sim://) no link watchdog is armed for it; in fast time its virtual clock
  // would outrun the keep-alives anyway.
  bool simulated() const override { return true; }

  // Until the board answers VER (the first answer after the held bytes): what it said before is
  // dropped. An error when hmc-emu ends first or the wait runs out.
  Status await_board(std::string_view probe) {
    if (Status sent = write(probe); !sent) return sent;
    LineSplitter lines;
    const Clock::time_point deadline = Clock::now() + kStartTimeout;
    while (Clock::now() < deadline) {
      detail::ReadOutcome got = detail::read_fd(master_.get(), std::chrono::milliseconds(50), detail::FdKind::kTerminal);
      lines.feed(got.bytes);
      while (const std::optional<Line> line = lines.next()) {
        Result<BoardFrame, Diagnostic> frame = decode_board_frame(line->text);
        if (frame && std::holds_alternative<Version>(*frame)) return Done{};
      }
      if (got.ended || exited()) return Error{lost_message()};
    }
    return Error{url_ + ": the emulated board did not answer VER within " +
                 std::to_string(std::chrono::duration_cast<std::chrono::seconds>(kStartTimeout).count()) +
                 " s of starting hmc-emu"};
  }

 private:
  bool exited() {
    if (child_ <= 0) return true;
    int status = 0;
    const pid_t done = ::waitpid(child_, &status, WNOHANG);
    if (done == child_) {
      child_ = -1;
      end_ = describe_end(status);
      return true;
    }
    return false;
  }

  std::string lost_message() {
    if (!exited()) {
      // The pseudo-terminal failed under a running hmc-emu: give it a moment to end and say how.
      for (int i = 0; i < 20 && !exited(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return "lost the emulated board " + url_ + ": hmc-emu ended" + (end_.empty() ? "" : " (" + end_ + ")") +
           " (its own message, if any, is above)";
  }

  // SIGTERM (hmc-emu ends at once), then SIGKILL if it has not ended in time.
  void end_child() {
    if (exited()) return;
    ::kill(child_, SIGTERM);
    const Clock::time_point deadline = Clock::now() + kEndTimeout;
    while (Clock::now() < deadline) {
      if (exited()) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ::kill(child_, SIGKILL);
    int status = 0;
    while (::waitpid(child_, &status, 0) < 0 && errno == EINTR) {
    }
    child_ = -1;
  }

  UniqueFd master_;
  pid_t child_;
  std::string url_;
  std::string description_;
  std::chrono::milliseconds write_timeout_;
  std::string end_;  // how hmc-emu ended, once it has
};

}  // namespace

Result<EmuPortOptions> parse_emu_url(std::string_view url) {
  constexpr std::string_view kScheme = "emu://";
  if (url.substr(0, kScheme.size()) != kScheme) return Error{std::string(url) + ": not an emu:// port"};
  const std::string_view rest = url.substr(kScheme.size());
  const size_t question = rest.find('?');
  EmuPortOptions options;
  options.image = std::string(rest.substr(0, question));
  if (question == std::string_view::npos) return options;
  for (const detail::UrlOption& option : detail::url_options(rest.substr(question + 1))) {
    const std::string_view key = option.key;
    const bool has_value = option.has_value;
    const std::string value(option.value);
    const auto needs_value = [&](const char* form) {
      return Error{std::string(url) + ": option '" + std::string(key) + "' needs a value: " + form};
    };
    if (key == "fast" || key == "nocrystal") {
      if (has_value) return Error{std::string(url) + ": option '" + std::string(key) + "' takes no value"};
      (key == "fast" ? options.fast : options.no_crystal) = true;
    } else if (key == "axis") {
      if (value.empty()) return needs_value("axis=M:LOW:HIGH:START");
      options.axes.push_back(value);
    } else if (key == "control") {
      if (value.empty()) return needs_value("control=HOST:PORT");
      options.control = value;
    } else if (key == "trace") {
      if (value.empty()) return needs_value("trace=FILE");
      options.trace = value;
    } else {
      return Error{std::string(url) + ": unknown option '" + std::string(key) +
                   "' (the options are fast, nocrystal, axis=M:LOW:HIGH:START, control=HOST:PORT and trace=FILE)"};
    }
  }
  return options;
}

Result<std::unique_ptr<Transport>> open_emu_port(std::string_view url, const PortOptions& port) {
  Result<EmuPortOptions> parsed = parse_emu_url(url);
  if (!parsed) return parsed.error();
  const EmuPortOptions& options = *parsed;
  // A named image is checked first: its mistake is the one to report.
  if (!options.image.empty()) {
    if (Result<std::string> named = find_image(options.image, ""); !named) return named.error();
  }
  Result<std::string> emulator = find_emulator();
  if (!emulator) return emulator.error();
  Result<std::string> image = find_image(options.image, *emulator);
  if (!image) return image.error();

  std::vector<std::string> args = {*emulator, *image, "--quiet", "--hold-input", kHoldInputSeconds,
                                   "--baud", std::to_string(port.baud)};
  if (options.fast) args.emplace_back("--fast");
  if (options.no_crystal) args.emplace_back("--no-crystal");
  for (const std::string& axis : options.axes) args.insert(args.end(), {"--axis", axis});
  if (!options.control.empty()) args.insert(args.end(), {"--control", options.control});
  if (!options.trace.empty()) args.insert(args.end(), {"--trace", options.trace});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const std::string name(url);
  const auto failed = [&](const std::string& what) { return Error{name + ": cannot " + what + ": " + strerror(errno)}; };
  UniqueFd master(::posix_openpt(O_RDWR | O_NOCTTY));
  if (master.get() < 0) return failed("open a pseudo-terminal");
  char slave_name[PATH_MAX];
  if (::fcntl(master.get(), F_SETFD, FD_CLOEXEC) != 0 || ::grantpt(master.get()) != 0 ||
      ::unlockpt(master.get()) != 0 || ::ptsname_r(master.get(), slave_name, sizeof slave_name) != 0) {
    return failed("set up a pseudo-terminal");
  }
  UniqueFd slave(::open(slave_name, O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (slave.get() < 0) return failed(std::string("open ") + slave_name);
  termios modes{};
  if (::tcgetattr(slave.get(), &modes) != 0) return failed("read the pseudo-terminal's modes");
  ::cfmakeraw(&modes);  // bytes as they are, both ways
  if (::tcsetattr(slave.get(), TCSANOW, &modes) != 0) return failed("set the pseudo-terminal raw");
  if (::fcntl(master.get(), F_SETFL, O_NONBLOCK) != 0) return failed("make the pseudo-terminal non-blocking");

  const pid_t parent = ::getpid();
  const std::string exec_failed = "hmc: cannot run " + *emulator + "\n";
  const pid_t child = ::fork();
  if (child < 0) return failed("start hmc-emu");
  if (child == 0) {
    // Only async-signal-safe calls from here to exec.
    ::setpgid(0, 0);  // the terminal's Ctrl-C is hmc's to handle
    // Dies with hmc, even with SIGKILL; and hmc may have died before this line.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    sigset_t none;
    ::sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    if (::dup2(slave.get(), STDIN_FILENO) < 0 || ::dup2(slave.get(), STDOUT_FILENO) < 0) ::_exit(127);
    ::execv(argv[0], argv.data());
    const ssize_t ignored = ::write(STDERR_FILENO, exec_failed.data(), exec_failed.size());
    static_cast<void>(ignored);
    ::_exit(127);
  }
  slave = UniqueFd();  // the child's now: its end is the pseudo-terminal's hang-up
  const std::string description = "emulated board " + name + " (hmc-emu " + *image + ", " +
                                  (options.fast ? "fast" : "real time") + ", a new board for this command)";
  auto transport = std::make_unique<EmuTransport>(std::move(master), child, name, description, port);
  Result<std::string, Diagnostic> probe = encode(VersionQuery{});
  if (!probe) return Error{name + ": cannot encode VER"};
  if (Status up = transport->await_board(*probe + "\n"); !up) return up.error();
  return std::unique_ptr<Transport>(std::move(transport));
}

}  // namespace hmc
