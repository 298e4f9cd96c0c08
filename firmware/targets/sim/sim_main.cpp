// hmc-sim: the firmware core on a simulated board (sim_board.h), serving the board's serial
// protocol on standard input and output, TCP or a pseudo-terminal, in real or fast virtual
// time, with switch events injected from a script or a control channel (docs/sim.md).
#include <signal.h>
#include <string.h>
#include <time.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "sim_board.h"
#include "sim_io.h"
#include "sim_options.h"
#include "sim_script.h"

namespace hmc::sim {
namespace {

volatile sig_atomic_t g_stop_requested = 0;
void request_stop(int) { g_stop_requested = 1; }

constexpr Ticks kMillisecond = hal::kTicksPerSecond / 1000u;
// Real time: while the board is busy, virtual time catches up with the wall clock at least
// this often, and at each byte's stop bit on the transmit wire: an answer's first bytes leave
// within about this long of when they would, the rest on time.
constexpr Ticks kBusySlice = kMillisecond;
// Real time, board idle: nothing reaches the link without input, so the loop only wakes this
// often, to keep the trace current.
constexpr Ticks kIdleSlice = 50 * kMillisecond;
// Fast: virtual time run between looks at the link and the control channel.
constexpr Ticks kFastSlice = kMillisecond;
// Fast: how far short of the link watchdog's deadline virtual time waits for the host.
constexpr Ticks kWatchdogMargin = 5 * kMillisecond;

class Simulator {
 public:
  Simulator(const SimOptions& options, SimBoard& board, Link& link, ControlServer* control,
            std::vector<ScriptEvent> script, std::ostream* trace, const sigset_t& wait_mask)
      : options_(options),
        board_(board),
        link_(link),
        control_(control),
        script_(std::move(script)),
        trace_(trace),
        wait_mask_(wait_mask) {}

  // Until a signal or the end of the session (finished()).
  void run() {
    origin_ = std::chrono::steady_clock::now();
    send_output();
    while (g_stop_requested == 0) {
      if (!options_.fast) {
        advance_to(wall_ticks());
      } else if (board_.busy()) {
        advance_to(fast_target());
      } else if (!script_done()) {
        advance_to(script_[next_event_].at);
      }
      if (!board_.receiving() && !board_.transmitting()) link_.input_taken();
      if (finished()) break;
      wait();
      if (!options_.fast) advance_to(wall_ticks());  // input is received at the time it came
      take_input();
    }
    if (trace_ != nullptr) trace_->flush();
  }

 private:
  bool script_done() const { return next_event_ == script_.size(); }

  // Standard input's end, or with --exit-when-idle nobody on the link, once nothing is left to do.
  bool finished() const {
    if (board_.busy() || !script_done() || !link_.detached()) return false;
    return link_.ends_at_detach() || options_.exit_when_idle;
  }

  Ticks wall_ticks() const {
    const auto ns = static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                              std::chrono::steady_clock::now() - origin_)
                                              .count());
    return ns / 1000u * hal::kTicksPerMicrosecond + ns % 1000u * hal::kTicksPerMicrosecond / 1000u;
  }

  // Fast virtual time outruns any host: a host's keep-alive, sent every so often in wall time,
  // would be seconds apart in virtual time and the link watchdog would brake every motor of a
  // live host. So virtual time stops just short of the watchdog's deadline and waits there, in
  // wall time, as long as the watchdog's timeout for a line from the host; only a host silent for
  // that long lets it fire.
  Ticks fast_target() {
    const Ticks target = board_.now() + kFastSlice;
    const fw::Controller& controller = board_.controller();
    // Short of the deadline by room for a line in transit (its bytes arrive in virtual time).
    const Ticks due = controller.watchdog_due() - kWatchdogMargin;
    if (controller.watchdog_ms() == 0 || target < due || board_.receiving()) {
      holding_ = false;
      return target;
    }
    const Ticks wall = wall_ticks();
    if (!holding_ || due != held_due_) {
      holding_ = true;
      held_due_ = due;
      held_until_ = wall + static_cast<Ticks>(controller.watchdog_ms()) * kMillisecond;
    }
    if (wall >= held_until_) return target;  // the host stayed silent: let the watchdog fire
    return due > board_.now() ? due - 1 : board_.now();
  }

  // Runs the board to `t`, applying the script's events at their exact times.
  void advance_to(Ticks t) {
    while (!script_done() && script_[next_event_].at <= t) {
      const ScriptEvent& event = script_[next_event_++];
      board_.run_until(event.at);
      send_output();
      apply(event.command);
    }
    board_.run_until(t);
    send_output();
  }

  // What is through the board's transmit wire (with --baud, each byte when its stop bit is).
  void send_output() {
    if (const std::string out = board_.take_output(); !out.empty()) link_.write(out);
  }

  // How long the wait may last, in ticks of wall time; nullopt: until input.
  std::optional<Ticks> wait_limit() const {
    std::optional<Ticks> limit;
    if (options_.fast) {
      if (board_.busy() || !script_done()) limit = 0;
      if (holding_) {
        const Ticks wall = wall_ticks();
        limit = held_until_ > wall ? std::min<Ticks>(held_until_ - wall, kIdleSlice) : 0;
      }
    } else {
      const Ticks now = board_.now();
      Ticks deadline =
          board_.busy() ? std::max(board_.next_event(), now + kBusySlice) : now + kIdleSlice;
      deadline = std::min(deadline, board_.next_output());
      if (!script_done()) deadline = std::min(deadline, script_[next_event_].at);
      const Ticks wall = wall_ticks();
      limit = deadline > wall ? deadline - wall : 0;
    }
    if (const int recheck = link_.recheck_ms(); recheck >= 0) {
      const Ticks ticks = static_cast<Ticks>(recheck) * kMillisecond;
      limit = limit ? std::min(*limit, ticks) : ticks;
    }
    return limit;
  }

  // Sleeps until input, the limit, or a signal (only let through while waiting, so one that
  // comes between the check of the flag and the wait still ends the wait).
  void wait() {
    const std::optional<Ticks> limit = wait_limit();
    if (trace_ != nullptr && limit != Ticks{0}) trace_->flush();
    poll_.clear();
    link_.arm(poll_);
    if (control_ != nullptr) control_->arm(poll_);
    timespec timeout{};
    if (limit) {
      const Ticks ns = *limit / hal::kTicksPerMicrosecond * 1000u;
      timeout.tv_sec = static_cast<time_t>(ns / 1000000000u);
      timeout.tv_nsec = static_cast<long>(ns % 1000000000u);
    }
    std::vector<pollfd>& fds = poll_.fds();
    if (ppoll(fds.data(), fds.size(), limit ? &timeout : nullptr, &wait_mask_) < 0) {
      for (pollfd& fd : fds) fd.revents = 0;  // a signal: nothing was found
    }
  }

  void take_input() {
    const std::string bytes = link_.service(poll_);
    if (!bytes.empty()) board_.send(bytes);
    if (control_ != nullptr) {
      control_->service(poll_, [this](std::string_view line) { return control_answer(line); });
    }
    send_output();
  }

  std::string control_answer(std::string_view line) {
    const Result<SimCommand> command = parse_command(line);
    if (!command) return "error: " + command.error;
    if (command.value->action == Action::kStatus) return status_json(board_);
    apply(*command.value);
    send_output();
    return "ok";
  }

  void apply(const SimCommand& command) {
    apply_command(board_, command);
  }

  const SimOptions& options_;
  SimBoard& board_;
  Link& link_;
  ControlServer* control_;
  std::vector<ScriptEvent> script_;
  size_t next_event_ = 0;
  bool holding_ = false;  // fast: virtual time waits short of the watchdog's deadline
  Ticks held_due_ = 0;
  Ticks held_until_ = 0;  // in wall time
  std::ostream* trace_;
  sigset_t wait_mask_;
  std::chrono::steady_clock::time_point origin_;
  PollSet poll_;
};

Result<std::vector<ScriptEvent>> load_script(const std::string& path, int& exit_code) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    exit_code = kExitIo;
    return Result<std::vector<ScriptEvent>>::fail("cannot read script '" + path +
                                                  "': " + strerror(errno));
  }
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Result<std::vector<ScriptEvent>> script = parse_script(text);
  if (!script) {
    exit_code = kExitUsage;
    script.error = path + ":" + script.error;
  }
  return script;
}

Result<std::unique_ptr<Link>> open_link(const SimOptions& options, Notes notes) {
  switch (options.link) {
    case LinkKind::kTcp:
      return open_tcp_link(options.tcp.host, options.tcp.port, notes);
    case LinkKind::kPty:
      return open_pty_link(notes);
    case LinkKind::kStdio:
      break;
  }
  return open_stdio_link();
}

int run(const SimOptions& options) {
  std::vector<ScriptEvent> script;
  if (!options.script.empty()) {
    int exit_code = kExitOk;
    Result<std::vector<ScriptEvent>> loaded = load_script(options.script, exit_code);
    if (!loaded) {
      std::cerr << "hmc-sim: " << loaded.error << '\n';
      return exit_code;
    }
    script = std::move(*loaded.value);
  }

  std::ofstream trace_file;
  std::ostream* trace = nullptr;
  if (options.trace == "-") {
    trace = &std::cerr;
  } else if (!options.trace.empty()) {
    trace_file.open(options.trace, std::ios::binary | std::ios::trunc);
    if (!trace_file) {
      std::cerr << "hmc-sim: cannot write trace '" << options.trace << "': " << strerror(errno)
                << '\n';
      return kExitIo;
    }
    trace = &trace_file;
  }

  const Notes notes = options.quiet ? nullptr : &std::cerr;
  Result<std::unique_ptr<Link>> link = open_link(options, notes);
  if (!link) {
    std::cerr << "hmc-sim: " << link.error << '\n';
    return kExitIo;
  }
  std::unique_ptr<ControlServer> control;
  if (options.control) {
    Result<std::unique_ptr<ControlServer>> opened =
        ControlServer::open(options.control->host, options.control->port, notes);
    if (!opened) {
      std::cerr << "hmc-sim: control: " << opened.error << '\n';
      return kExitIo;
    }
    control = std::move(*opened.value);
  }
  // The addresses are printed even with --quiet: they are how a client finds the board.
  if (const std::string text = (*link.value)->announcement(); !text.empty()) {
    std::cerr << "hmc-sim: " << text << '\n';
  }
  if (control) std::cerr << "hmc-sim: control listening on " << control->address() << '\n';
  std::cerr << std::flush;

  // SIGINT and SIGTERM stay blocked except inside the wait, which they end.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  sigset_t wait_mask;
  sigprocmask(SIG_BLOCK, &stop_signals, &wait_mask);
  sigdelset(&wait_mask, SIGINT);
  sigdelset(&wait_mask, SIGTERM);
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a peer gone is seen as a failed write

  SimBoard board(options.config);
  board.set_trace(trace);
  board.boot();
  Simulator simulator(options, board, **link.value, control.get(), std::move(script), trace,
                      wait_mask);
  simulator.run();
  return kExitOk;
}

}  // namespace
}  // namespace hmc::sim

int main(int argc, char** argv) {
  const hmc::sim::ParsedArgs args = hmc::sim::parse_args(argc, argv);
  if (!args.options) return args.exit_code;
  return hmc::sim::run(*args.options);
}
