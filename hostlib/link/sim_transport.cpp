// sim://: the simulated board as an in-process transport, kept "powered" between commands by a
// journal of everything the host sent, replayed when the next command opens the same board.
//
// Journal (one per board and option set, sim-NAME[-seed|-legacy][-baudN].journal):
//   hmc-sim-journal 1 seed=0 legacy=0 baud=115200   header: format version and the options
//   w TICK HEX                                       a write: the virtual tick it was sent at, its bytes
//   e TICK                                           a command disconnected at that tick
// Ticks only grow. The board is deterministic, so booting it and sending every write at its tick
// rebuilds exactly the state the last command left; virtual time does not pass between commands,
// except that lines the last command left unanswered are answered (to nobody) before the next.
#include "hmc/sim_transport.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "sim_board.h"
#include "transports.h"

namespace hmc {
namespace {

using sim::Ticks;
using Clock = std::chrono::steady_clock;

constexpr int kJournalVersion = 1;
// Fast: virtual time runs in steps of the board's main-loop period, which is when it writes,
// so a read returns soon after a byte is through the board's transmit wire.
constexpr Ticks kFastSlice = sim::kPollTicks;
// Real time: how long a read sleeps between catching the board up with the wall clock.
constexpr auto kRealTimeSleep = std::chrono::milliseconds(1);
// Fast: how far ahead of the link watchdog's deadline the reading host's keep-alive is sent.
constexpr Ticks kWatchdogMargin = 5 * hal::kTicksPerMicrosecond * 1000;

Ticks duration_ticks(std::chrono::nanoseconds duration) {
  const auto ns = static_cast<uint64_t>(std::max<int64_t>(duration.count(), 0));
  return ns / 1000u * hal::kTicksPerMicrosecond + ns % 1000u * hal::kTicksPerMicrosecond / 1000u;
}

bool name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-';
}

std::string to_hex(std::string_view bytes) {
  static const char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (const char c : bytes) {
    const auto u = static_cast<unsigned char>(c);
    out += kDigits[u >> 4];
    out += kDigits[u & 0xFu];
  }
  return out;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

std::optional<std::string> from_hex(std::string_view text) {
  if (text.size() % 2 != 0) return std::nullopt;
  std::string out;
  out.reserve(text.size() / 2);
  for (size_t i = 0; i < text.size(); i += 2) {
    const int high = hex_digit(text[i]);
    const int low = hex_digit(text[i + 1]);
    if (high < 0 || low < 0) return std::nullopt;
    out += static_cast<char>((high << 4) | low);
  }
  return out;
}

std::optional<Ticks> parse_tick(std::string_view text) {
  if (text.empty() || text.size() > 19) return std::nullopt;  // 19 digits never overflow 64 bits
  Ticks value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10u + static_cast<Ticks>(c - '0');
  }
  return value;
}

std::string journal_header(const SimPortOptions& options, uint32_t baud) {
  return "hmc-sim-journal " + std::to_string(kJournalVersion) + " seed=" + (options.seed ? "1" : "0") +
         " legacy=" + (options.legacy ? "1" : "0") + " baud=" + std::to_string(baud);
}

// Variants of one board that would behave differently never share a journal.
std::string journal_file_name(const SimPortOptions& options, uint32_t baud) {
  std::string name = "sim-" + options.name;
  if (options.seed) {
    name += "-seed";
  } else if (options.legacy) {
    name += "-legacy";
  }
  if (baud != kDefaultBaud) name += "-baud" + std::to_string(baud);
  return name + ".journal";
}

struct JournalWrite {
  Ticks at = 0;
  std::string bytes;
};

struct Journal {
  std::vector<JournalWrite> writes;
  Ticks end = 0;  // the last tick the journal mentions: where the board continues
};

// Reads a whole journal; an error names the first line that cannot be replayed.
Result<Journal> parse_journal(const std::string& text, const std::string& header) {
  Journal journal;
  size_t line_start = 0;
  size_t number = 0;
  while (line_start < text.size()) {
    ++number;
    const size_t line_end = text.find('\n', line_start);
    const auto bad = [&](const std::string& what) { return Error{"line " + std::to_string(number) + ": " + what}; };
    if (line_end == std::string::npos) return bad("cut short");
    const std::string_view line(text.data() + line_start, line_end - line_start);
    line_start = line_end + 1;
    if (number == 1) {
      if (line != header) return bad("written for other options or by another version");
      continue;
    }
    if (line.size() < 3 || line[1] != ' ' || (line[0] != 'w' && line[0] != 'e')) return bad("not a journal line");
    const std::string_view rest = line.substr(2);
    const size_t blank = rest.find(' ');
    const std::optional<Ticks> at = parse_tick(rest.substr(0, blank));
    if (!at) return bad("bad tick");
    if (*at < journal.end) return bad("time goes backward");
    journal.end = *at;
    if (line[0] == 'e') {
      if (blank != std::string_view::npos) return bad("not a journal line");
      continue;
    }
    if (blank == std::string_view::npos) return bad("a write without bytes");
    std::optional<std::string> bytes = from_hex(rest.substr(blank + 1));
    if (!bytes || bytes->empty()) return bad("bad bytes");
    journal.writes.push_back({*at, std::move(*bytes)});
  }
  if (number == 0) return Error{"empty"};
  return journal;
}

std::string errno_text(int error) { return strerror(error); }

Status write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return Error{errno_text(errno)};
    }
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  return Done{};
}

Result<std::string> read_all(int fd) {
  std::string text;
  char buffer[65536];
  off_t offset = 0;
  while (true) {
    const ssize_t n = ::pread(fd, buffer, sizeof buffer, offset);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Error{errno_text(errno)};
    }
    if (n == 0) return text;
    text.append(buffer, static_cast<size_t>(n));
    offset += n;
  }
}

class SimTransport final : public Transport {
 public:
  SimTransport(SimPortOptions options, std::unique_ptr<sim::SimBoard> board, int journal_fd, std::string journal_path,
               std::string note)
      : options_(std::move(options)),
        board_(std::move(board)),
        journal_fd_(journal_fd),
        journal_path_(std::move(journal_path)),
        note_(std::move(note)),
        base_(board_->now()),
        origin_(Clock::now()) {}

  ~SimTransport() override {
    // The motors are not stopped: like a real board, this one runs on when the host lets go,
    // and the next command finds it where this one's clock ended.
    if (!options_.fast) board_->run_until(wall_ticks());
    if (options_.keep) (void)write_all(journal_fd_, "e " + std::to_string(board_->now()) + "\n");
    if (trace_file_.is_open()) trace_file_.flush();
    board_->set_trace(nullptr);
    ::close(journal_fd_);  // releases the lock
  }

  SimTransport(const SimTransport&) = delete;
  SimTransport& operator=(const SimTransport&) = delete;

  Status open_trace() {
    if (options_.trace.empty()) return Done{};
    trace_file_.open(options_.trace, std::ios::binary | std::ios::app);
    if (!trace_file_) {
      return Error{"cannot write the trace of sim://" + options_.name + " to '" + options_.trace +
                   "': " + errno_text(errno)};
    }
    board_->set_trace(&trace_file_);
    return Done{};
  }

  Status write(std::string_view bytes) override {
    if (bytes.empty()) return Done{};
    if (!options_.fast) board_->run_until(wall_ticks());
    // Journaled before the board gets them, so the saved state never lacks what the board saw.
    if (options_.keep) {
      const Status saved = write_all(journal_fd_, "w " + std::to_string(board_->now()) + " " + to_hex(bytes) + "\n");
      if (!saved) {
        return Error{"cannot save the state of sim://" + options_.name + " to " + journal_path_ + ": " +
                     saved.error().message};
      }
    }
    board_->send(std::string(bytes));
    return Done{};
  }

  // Fast virtual time outruns the host's keep-alives, which it sends in wall time. The host is
  // this process, alive while it reads: a blank line is sent for it short of the watchdog's
  // deadline, so an armed watchdog fires here only when the host stops reading (or is gone and
  // the saved state is replayed), as on a board whose host keeps up.
  Status keep_link_alive() {
    const fw::Controller& controller = board_->controller();
    if (controller.watchdog_ms() == 0 || board_->receiving() ||
        board_->now() + kFastSlice + kWatchdogMargin < controller.watchdog_due()) {
      return Done{};
    }
    return write("\n");
  }

  Result<std::string> read(std::chrono::milliseconds timeout) override {
    std::string out = board_->take_output();
    if (options_.fast) {
      const Ticks end = board_->now() + duration_ticks(timeout);
      while (out.empty() && board_->now() < end) {
        if (Status alive = keep_link_alive(); !alive) return alive.error();
        board_->run_until(std::min(board_->now() + kFastSlice, end));
        out = board_->take_output();
      }
      // A host reads a line once it is whole: wait for the rest of the one begun.
      while (!out.empty() && out.back() != '\n' && board_->transmitting()) {
        board_->run_until(board_->next_output());
        out += board_->take_output();
      }
    } else {
      const Clock::time_point deadline = Clock::now() + timeout;
      while (true) {
        board_->run_until(wall_ticks());
        out += board_->take_output();
        if (!out.empty()) break;
        const Clock::time_point now = Clock::now();
        if (now >= deadline) break;
        std::this_thread::sleep_for(std::min<Clock::duration>(kRealTimeSleep, deadline - now));
      }
    }
    // Another program may be watching the trace.
    if (trace_file_.is_open()) trace_file_.flush();
    return out;
  }

  std::string description() const override {
    std::string text = "simulated board sim://" + options_.name + " (" + (options_.fast ? "fast" : "real time");
    if (options_.seed) {
      text += ", seed firmware";
    } else if (options_.legacy) {
      text += ", legacy rules";
    }
    if (!options_.keep) text += ", not saved";
    text += ")";
    if (!note_.empty()) text += "; " + note_;
    return text;
  }

  bool simulated() const override { return true; }
  bool seed_firmware() const override { return options_.seed; }

 private:
  // Real time: virtual time follows the wall clock from the open, going on from the replayed state.
  Ticks wall_ticks() const {
    return base_ + duration_ticks(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - origin_));
  }

  SimPortOptions options_;
  std::unique_ptr<sim::SimBoard> board_;
  int journal_fd_;
  std::string journal_path_;
  std::string note_;
  Ticks base_;
  Clock::time_point origin_;
  std::ofstream trace_file_;
};

// Closes a file descriptor unless released.
}  // namespace

Result<SimPortOptions> parse_sim_url(std::string_view url) {
  constexpr std::string_view kScheme = "sim://";
  if (url.substr(0, kScheme.size()) != kScheme) {
    return Error{"'" + std::string(url) + "' is not a simulated board: those are written sim://[NAME][?OPTION&...]"};
  }
  SimPortOptions options;
  const std::string_view rest = url.substr(kScheme.size());
  const size_t question = rest.find('?');
  const std::string_view name = rest.substr(0, question);
  if (!name.empty()) {
    if (name.front() == '.' || !std::all_of(name.begin(), name.end(), name_char)) {
      return Error{std::string(url) + ": the board's name '" + std::string(name) +
                   "' may hold only letters, digits, '_', '-' and '.' (not first)"};
    }
    options.name = std::string(name);
  }
  if (question == std::string_view::npos) return options;

  for (const detail::UrlOption& option : detail::url_options(rest.substr(question + 1))) {
    const std::string_view key = option.key;
    const bool has_value = option.has_value;
    const std::string_view value = option.value;
    bool* flag = nullptr;
    bool flag_value = true;
    if (key == "fast") {
      flag = &options.fast;
    } else if (key == "seed") {
      flag = &options.seed;
    } else if (key == "legacy") {
      flag = &options.legacy;
    } else if (key == "fresh") {
      flag = &options.fresh;
    } else if (key == "nosave") {
      flag = &options.keep;
      flag_value = false;
    } else if (key == "trace") {
      if (value.empty()) return Error{std::string(url) + ": option 'trace' needs a file: trace=PATH"};
      options.trace = std::string(value);
      continue;
    } else {
      return Error{std::string(url) + ": unknown option '" + std::string(key) +
                   "' (the options are fast, seed, legacy, fresh, nosave and trace=PATH)"};
    }
    if (has_value) return Error{std::string(url) + ": option '" + std::string(key) + "' takes no value"};
    *flag = flag_value;
  }
  return options;
}

Result<std::string> sim_state_directory() {
  const auto env = [](const char* name) -> std::string {
    const char* value = std::getenv(name);
    return value != nullptr ? value : "";
  };
  if (std::string dir = env("HMC_SIM_STATE"); !dir.empty()) return dir;
  if (const std::string dir = env("XDG_STATE_HOME"); !dir.empty()) return dir + "/hmc";
  if (const std::string home = env("HOME"); !home.empty()) return home + "/.local/state/hmc";
  return Error{"no directory for the simulated boards' state: set HMC_SIM_STATE (or HOME)"};
}

Result<std::unique_ptr<Transport>> open_sim_port(std::string_view url, const PortOptions& port) {
  Result<SimPortOptions> parsed = parse_sim_url(url);
  if (!parsed) return parsed.error();
  SimPortOptions options = std::move(parsed.value());
  if (options.seed) options.legacy = true;  // the seed firmware's rules are the legacy ones
  const std::string board_url = "sim://" + options.name;

  Result<std::string> dir = sim_state_directory();
  if (!dir) return dir.error();
  std::error_code ec;
  std::filesystem::create_directories(*dir, ec);
  if (ec) {
    return Error{"cannot create the directory for the state of " + board_url + ", '" + *dir + "': " + ec.message() +
                 " (set HMC_SIM_STATE to a writable directory)"};
  }
  const std::string path = *dir + "/" + journal_file_name(options, port.baud);
  UniqueFd fd(::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644));
  if (fd.get() < 0) {
    return Error{"cannot open the state of " + board_url + ", '" + path + "': " + errno_text(errno) +
                 " (set HMC_SIM_STATE to a writable directory)"};
  }
  while (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    if (errno == EWOULDBLOCK) return Error{board_url + " is in use by another program"};
    return Error{"cannot lock the state of " + board_url + ", '" + path + "': " + errno_text(errno)};
  }

  const std::string header = journal_header(options, port.baud);
  std::optional<Journal> journal;
  std::string note;
  if (options.fresh) {
    if (options.keep && ::ftruncate(fd.get(), 0) != 0) {
      return Error{"cannot forget the state of " + board_url + ", '" + path + "': " + errno_text(errno)};
    }
  } else {
    // A journal that cannot be replayed never keeps the board from opening: it starts fresh.
    Result<std::string> text = read_all(fd.get());
    std::string problem;
    if (!text) {
      problem = "its saved state could not be read (" + text.error().message + ")";
    } else if (!text->empty()) {
      Result<Journal> read = parse_journal(*text, header);
      if (read) {
        journal = std::move(read.value());
      } else {
        problem = "its saved state could not be replayed (" + read.error().message + ")";
      }
    }
    if (!problem.empty()) {
      note = problem + ", so it started fresh";
      if (options.keep) {
        // Set aside for a person to look at; the board starts over in a new journal.
        const std::string aside = path + ".bad";
        if (text) {
          std::ofstream(aside, std::ios::binary | std::ios::trunc) << *text;
          note += "; the old journal is in " + aside;
        }
        if (::ftruncate(fd.get(), 0) != 0) {
          return Error{"cannot replace the unreadable state of " + board_url + ", '" + path +
                       "': " + errno_text(errno)};
        }
      }
    }
  }
  if (options.keep && !journal) {
    const Status started = write_all(fd.get(), header + "\n");
    if (!started) {
      return Error{"cannot write the state of " + board_url + ", '" + path + "': " + started.error().message};
    }
  }

  sim::SimConfig config;
  config.options.self_test = false;  // a board that appears on demand does not move by itself
  config.options.legacy = options.legacy;
  config.options.replies = !options.seed;
  config.baud = port.baud;
  auto board = std::make_unique<sim::SimBoard>(config);
  board->boot();
  if (journal) {
    // What the board sent back then was read then, or lost when that command let go: only the
    // state matters now.
    for (const JournalWrite& write : journal->writes) {
      board->run_until(write.at);
      board->send(write.bytes);
      (void)board->take_output();
    }
    board->run_until(journal->end);
    // Lines that command sent and let go of before their answers came are read and answered
    // now, to nobody: a reply left over must never be taken for the answer to this command's
    // lines. (Deterministic: a later replay passes through the same ticks.)
    while (board->receiving()) board->run_until(board->next_event());
    board->run_for(sim::kPollTicks);  // the main loop handles the last line
    board->drop_output();
  }

  auto transport = std::make_unique<SimTransport>(std::move(options), std::move(board), fd.release(), path, note);
  if (Status traced = transport->open_trace(); !traced) return traced.error();
  return std::unique_ptr<Transport>(std::move(transport));
}

}  // namespace hmc
