// hmc-emu: the SAMD21 board emulator. Runs the exact firmware image (the ELF the firmware preset
// builds) on an emulated Cortex-M0+ with the chip's peripherals and the board's devices, and
// serves the command UART (SERCOM5) on standard input/output or a pseudo-terminal, in real or
// unthrottled ("fast") virtual time. docs/emu.md describes what is modelled.
#include <poll.h>
#include <signal.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <fstream>
#include <sstream>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "board/board.h"
#include "board/trace.h"
#include "bootloader/bare_chip.h"
#include "bootloader/bootloader_session.h"
#include "chip/chip.h"
#include "chip/port.h"
#include "chip/sercom.h"
#include "chip/system.h"
#include "cpu/cpu.h"
#include "elf/elf_image.h"
#include "front/events.h"
#include "front/links.h"
#include "front/raw_image.h"
#include "sim_io.h"
#include "sim_options.h"
#include "sim_script.h"

namespace hmc::emu {
namespace {

enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 2,      // a bad option
  kExitIo = 3,         // the image file or the pseudo-terminal could not be used
  kExitImage = 4,      // not a SAMD21 image: not ARM, linked elsewhere, a bad vector table
  kExitViolation = 5,  // the image broke a rule of the chip, faulted, or the watchdog expired
  kExitTimeLimit = 6,  // --max-time reached
};

constexpr uint64_t kPsPerMs = 1000000000ull;
constexpr unsigned kUartSercom = 5;  // the command UART (firmware/targets/samd21/board.h)
constexpr uint32_t kAppBase = 0x2000;  // behind the bootloader (HARDWARE.md)

volatile sig_atomic_t g_stop = 0;
void request_stop(int) { g_stop = 1; }

struct Options {
  std::string image;
  bool pty = false;
  std::string tcp;      // --tcp HOST:PORT, as hmc-sim's
  std::string control;  // --control HOST:PORT: hmc-sim's control channel
  double hold_input_s = 0;  // the host's bytes wait until this virtual time (and the first line)
  std::string raw_at = "0x2000";  // where a raw .bin image starts
  bool fast = false;
  uint32_t baud = 115200;
  double max_time_s = 0;
  bool no_crystal = false;
  std::string bootloader = "auto";  // auto, yes, no
  bool watchdog_resets = false;
  bool run_fault_handler = false;
  bool quiet = false;
  bool stats = false;
  double measure_from_s = 0;  // --stats counts from this virtual time on
  std::string count_calls;     // --stats counts this function's calls
  uint32_t count_calls_at = 0;  // its address, from the image's symbols
  // Start in the bootloader (docs/emu.md, "Flashing"): the native USB port, the UF2 drive.
  std::string usb_pty;
  std::string uf2_drive;
  bool touch_to_enter = false;
  std::string script;  // hmc-sim's script language (docs/sim.md, "Injected events")
  std::vector<std::string> axes;  // hmc-sim's --axis M:LOW:HIGH:START
  double stall_at_s = 0;          // the CPU stops executing here (0: never), until a reset
  std::string trace;              // hmc-sim's trace format (docs/sim.md, "Trace"); "-": stderr
};

// The bootloader's run before the first boot: the flash starts with the image's bytes (or erased
// without an image), the host flashes through the USB port or the UF2 drive, and the board then
// boots what the flash holds from 0x2000. `image` becomes that flash content; the image's
// function names stay only if the flash still holds the image's bytes.
int run_bootloader_first(const Options& options, ElfImage& image) {
  BareChip chip;
  for (const Segment& s : image.segments) {
    if (!chip.nvm().load_flash(s.address, s.bytes)) {
      std::cerr << "hmc-emu: the image has bytes at 0x" << std::hex << s.address << std::dec
                << ", outside the 256 KB flash\n";
      return kExitImage;
    }
  }
  BootloaderPorts ports;
  ports.usb = !options.usb_pty.empty();
  ports.usb_link = options.usb_pty;
  ports.uf2_drive = options.uf2_drive;
  ports.touch_to_enter = options.touch_to_enter;
  std::string error;
  const auto say = [&](const std::string& line) {
    if (!options.quiet || line.rfind("usb pty", 0) == 0 || line.rfind("uf2 drive", 0) == 0)
      std::cerr << "hmc-emu: " << line << std::endl;
  };
  switch (run_bootloader(chip, ports, g_stop, say, error)) {
    case BootloaderEnd::kError: std::cerr << "hmc-emu: " << error << '\n'; return kExitIo;
    case BootloaderEnd::kStopped: return kExitOk;
    case BootloaderEnd::kStartApplication: break;
  }
  const std::vector<uint8_t>& flash = chip.nvm().flash();
  bool same = !image.segments.empty();
  for (const Segment& s : image.segments)
    same = same && std::equal(s.bytes.begin(), s.bytes.end(), flash.begin() + s.address);
  ElfImage flashed;
  flashed.segments.push_back(Segment{kAppBase, std::vector<uint8_t>(flash.begin() + kAppBase, flash.end())});
  flashed.entry = image.entry;
  if (same) flashed.functions = image.functions;
  image = std::move(flashed);
  return -1;
}

// One power cycle of the board: the chip, the CPU on it, the image in its flash.
struct Machine {
  std::unique_ptr<Chip> chip;
  std::unique_ptr<Cpu> cpu;
};

std::string format_seconds(uint64_t ps) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f s", static_cast<double>(ps) / 1e12);
  return text;
}

class Emulator {
 public:
  Emulator(const Options& options, const ElfImage& image, sim::Link& link,
           std::vector<sim::ScriptEvent> script, sim::ControlServer* control)
      : options_(options), image_(image), link_(link), script_(std::move(script)), control_(control) {}

  bool power_on(uint8_t reset_cause, std::string& error) {
    ChipOptions chip_options;
    chip_options.crystal = !options_.no_crystal;
    const uint32_t base = image_.lowest_address();
    chip_options.after_bootloader =
        options_.bootloader == "yes" || (options_.bootloader == "auto" && base == kAppBase);
    chip_options.wire_baud = options_.baud;
    chip_options.watchdog_resets = options_.watchdog_resets;
    const uint64_t carried_ps = machine_.chip ? machine_.chip->now_ps() : 0;
    machine_.cpu.reset();
    booted_ = false;
    machine_.chip = std::make_unique<Chip>(chip_options);
    machine_.chip->pm().set_reset_cause(reset_cause);
    time_offset_ps_ += carried_ps;
    if (trace_ != nullptr) {
      trace_->set_offset_ps(time_offset_ps_);
      machine_.chip->board().set_trace(trace_);
    }
    CpuOptions cpu_options;
    cpu_options.run_fault_handler = options_.run_fault_handler;
    cpu_options.count_calls_at = options_.count_calls_at;
    for (const std::string& text : options_.axes) {
      const sim::AxisOption axis = *sim::parse_axis(text).value;  // checked by the option
      machine_.chip->board().set_axis(axis.motor - 1u, axis.axis);
    }
    machine_.cpu = std::make_unique<Cpu>(*machine_.chip, image_, cpu_options);
    if (!machine_.cpu->init(error)) return false;
    return machine_.cpu->reset(base, error);
  }

  uint64_t now_ps() const { return time_offset_ps_ + machine_.chip->now_ps(); }

  // What --stats reports: the figures since the measurement began (--measure-from).
  struct Snapshot {
    uint64_t ps = 0;
    uint64_t cycles = 0;
    uint64_t instructions = 0;
    uint64_t flash_wait_cycles = 0;
    uint64_t thread_cycles = 0;
    uint64_t calls = 0;
    std::map<unsigned, Cpu::HandlerFigures> handlers;
    uint64_t steps[3] = {};
  };
  Snapshot snapshot() const {
    Snapshot s;
    s.ps = now_ps();
    s.cycles = machine_.chip->cycles();
    s.instructions = machine_.cpu->instructions();
    s.flash_wait_cycles = machine_.cpu->flash_wait_cycles();
    s.thread_cycles = machine_.cpu->thread_cycles();
    s.calls = machine_.cpu->calls();
    s.handlers = machine_.cpu->handler_figures();
    for (unsigned m = 0; m < 3; ++m) s.steps[m] = machine_.chip->board().axis(m).steps;
    return s;
  }
  const Snapshot& measure_start() const { return measure_start_; }

  int run() {
    const auto origin = std::chrono::steady_clock::now();
    const uint64_t limit =
        options_.max_time_s > 0 ? static_cast<uint64_t>(options_.max_time_s * 1e12) : UINT64_MAX;
    uint64_t quiet_since = 0;
    bool input_ended = false;
    while (g_stop == 0) {
      uint64_t target = now_ps() + kPsPerMs;
      if (!options_.fast) {
        const auto wall = std::chrono::steady_clock::now() - origin;
        target = static_cast<uint64_t>(
                     std::chrono::duration_cast<std::chrono::nanoseconds>(wall).count()) * 1000u;
        // Behind the wall clock (the emulation is slower than the chip): catch up in slices,
        // looking at the link between them.
        if (target > now_ps() + 10 * kPsPerMs) target = now_ps() + 10 * kPsPerMs;
      }
      if (target > limit) target = limit;
      if (!script_done() && event_ps(script_[next_event_]) < target) {
        target = std::max(event_ps(script_[next_event_]), now_ps());
      }
      if (options_.stall_at_s > 0 && !stall_done_ && now_ps() >= stall_at_ps()) {
        stalled_ = stall_done_ = true;
      }
      if (!stalled_ && options_.stall_at_s > 0 && !stall_done_ && target > stall_at_ps()) {
        target = std::max(stall_at_ps(), now_ps());
      }
      if (stalled_ && target > now_ps()) {
        // A hung CPU: no instruction runs, no interrupt is taken; the clocks and the
        // peripherals (the watchdog among them) go on.
        Chip& chip = *machine_.chip;
        chip.charge_cycles(chip.cycles_at(target - time_offset_ps_) - chip.cycles());
        chip.advance();
      } else if (target > now_ps()) {
        machine_.cpu->run_until(target - time_offset_ps_);
      }
      if (!measuring_ && now_ps() >= static_cast<uint64_t>(options_.measure_from_s * 1e12)) {
        measuring_ = true;
        measure_start_ = snapshot();
        machine_.chip->board().reset_pulse_figures();
      }
      if (apply_due_events()) quiet_since = now_ps();
      Chip& chip = *machine_.chip;
      Sercom& uart = chip.sercom(kUartSercom);
      if (const std::string out = uart.take_output(); !out.empty()) {
        link_.write(out);
        quiet_since = now_ps();
        if (out.find('\n') != std::string::npos) booted_ = true;
      }
      if (taking_input() && !held_.empty()) {
        uart.host_send(held_);
        held_.clear();
      }
      if (!chip.violation_message().empty()) {
        const uint32_t pc = machine_.cpu->pc();
        std::cerr << "hmc-emu: stopped at " << format_seconds(now_ps()) << ": "
                  << chip.violation_message() << "\nhmc-emu: PC in "
                  << machine_.cpu->where(pc) << '\n';
        return kExitViolation;
      }
      if (chip.reset_requested()) {
        const uint8_t cause = static_cast<uint8_t>(chip.pm().read(0x38, 1));
        if (!options_.quiet) {
          std::cerr << "hmc-emu: chip reset at " << format_seconds(now_ps()) << " (RCAUSE 0x"
                    << std::hex << unsigned{cause} << std::dec << ")\n";
        }
        std::string error;
        stalled_ = false;
        if (!power_on(cause, error)) {
          std::cerr << "hmc-emu: " << error << '\n';
          return kExitImage;
        }
        continue;
      }
      if (now_ps() >= limit) {
        std::cerr << "hmc-emu: --max-time reached at " << format_seconds(now_ps())
                  << " of virtual time; PC in " << machine_.cpu->where(machine_.cpu->pc())
                  << '\n';
        return kExitTimeLimit;
      }
      // Standard input ended: finish once every byte is in and the answers have been quiet
      // for 200 ms of virtual time.
      if (input_ended && script_done() && held_.empty() && !uart.receiving() && !uart.transmitting() &&
          now_ps() - quiet_since > 200 * kPsPerMs) {
        return kExitOk;
      }
      // Wait for input: not at all in fast mode, until the next millisecond in real time.
      poll_.clear();
      link_.arm(poll_);
      if (control_ != nullptr) control_->arm(poll_);
      std::vector<pollfd>& fds = poll_.fds();
      int timeout_ms = options_.fast ? 0 : 1;
      if (input_ended) timeout_ms = 0;
      if (poll(fds.data(), fds.size(), timeout_ms) < 0) {
        for (pollfd& fd : fds) fd.revents = 0;
      }
      const std::string in = link_.service(poll_);
      if (!in.empty()) {
        // Until the board's first line (its boot event) the host's bytes wait: on the board
        // they would reach a receiver not yet enabled and be lost (docs/emu.md).
        if (taking_input()) uart.host_send(in);
        else held_ += in;
        quiet_since = now_ps();
      }
      if (held_.empty() && !uart.receiving()) link_.input_taken();
      if (control_ != nullptr) {
        control_->service(poll_, [this](std::string_view line) { return control_answer(line); });
      }
      if (link_.detached() && link_.ends_at_detach() && !input_ended) {
        input_ended = true;
        quiet_since = now_ps();
      }
    }
    return kExitOk;
  }

  const Machine& machine() const { return machine_; }
  void set_trace(Trace* trace) { trace_ = trace; }

 private:
  const Options& options_;
  const ElfImage& image_;
  sim::Link& link_;
  Machine machine_;
  uint64_t time_offset_ps_ = 0;
  Trace* trace_ = nullptr;
  sim::PollSet poll_;
  bool booted_ = false;  // the board has sent its first line since power-on
  bool measuring_ = false;
  Snapshot measure_start_;
  std::string held_;     // host bytes waiting for it (and for --hold-input)
  std::vector<sim::ScriptEvent> script_;
  size_t next_event_ = 0;
  sim::ControlServer* control_;
  bool stalled_ = false;     // --stall-at reached: the CPU executes nothing until a reset
  bool stall_done_ = false;  // the stall happens once
  uint64_t stall_at_ps() const { return static_cast<uint64_t>(options_.stall_at_s * 1e12); }

  bool script_done() const { return next_event_ == script_.size(); }
  bool taking_input() const {
    return booted_ && now_ps() >= static_cast<uint64_t>(options_.hold_input_s * 1e12);
  }
  void send_line(const std::string& line) {
    if (taking_input()) machine_.chip->sercom(kUartSercom).host_send(line);
    else held_ += line;
  }
  // The control channel: one command a line, applied at once (docs/sim.md, "The control channel").
  std::string control_answer(std::string_view line) {
    const sim::Result<sim::SimCommand> command = sim::parse_command(line);
    if (!command) return "error: " + command.error;
    if (command.value->action == sim::Action::kStatus) return emu_status_json(machine_.chip->board(), now_ps());
    apply_event(*machine_.chip, *command.value, [this](const std::string& text) { send_line(text); });
    return "ok";
  }
  // Script times are hmc-sim's ticks (1/48 µs) since the first power-on.
  static uint64_t event_ps(const sim::ScriptEvent& event) { return event.at * 1000000u / 48u; }
  // The script's events due by now: a line onto the UART's wire, a switch, a driver fault.
  // True when any was applied (the run then waits for the board's answer before ending).
  bool apply_due_events() {
    const size_t first = next_event_;
    while (!script_done() && event_ps(script_[next_event_]) <= now_ps()) {
      apply_event(*machine_.chip, script_[next_event_++].command,
                  [this](const std::string& text) { send_line(text); });
    }
    return next_event_ != first;
  }
};

int run(const Options& options) {
  ElfImage image;
  std::string error;
  const bool bootloader_first = !options.usb_pty.empty() || !options.uf2_drive.empty();
  if (options.image.empty() && !bootloader_first) {
    std::cerr << "hmc-emu: give the firmware ELF, or --usb-pty/--uf2-drive to flash one first\n";
    return kExitUsage;
  }
  const bool raw = is_raw_image(options.image);
  if (!options.image.empty() &&
      !(raw ? load_raw_image(options.image, options.raw_at == "0x0" ? 0 : kAppBase, image, error)
            : load_elf(options.image, image, error))) {
    std::cerr << "hmc-emu: " << error << '\n';
    return errno == ENOENT || error.rfind("cannot read", 0) == 0 ? kExitIo : kExitImage;
  }
  const uint32_t base = image.lowest_address();
  if (!image.segments.empty() && base != 0 && base != kAppBase) {
    std::cerr << "hmc-emu: '" << options.image << "' is linked at 0x" << std::hex << base
              << std::dec << ": a SAMD21 image starts at 0x0 (no bootloader) or 0x2000 (behind "
              << "the bootloader)\n";
    return kExitImage;
  }
  Options resolved = options;
  if (!options.count_calls.empty()) {
    const std::vector<uint32_t> found = image.functions_named(options.count_calls);
    if (found.size() != 1) {
      std::cerr << "hmc-emu: --count-calls '" << options.count_calls << "': "
                << (found.empty() ? "no function of that name in the image's symbols"
                                  : std::to_string(found.size()) + " functions of that name: give the symbol as written")
                << '\n';
      return kExitUsage;
    }
    resolved.count_calls_at = found[0];
  }
  const sim::Notes notes = options.quiet ? nullptr : &std::cerr;
  sim::Result<std::unique_ptr<sim::Link>> link = open_link(options.pty, options.tcp, notes);
  if (!link) {
    std::cerr << "hmc-emu: " << link.error << '\n';
    return kExitIo;
  }
  std::unique_ptr<sim::ControlServer> control;
  if (!options.control.empty()) {
    const sim::HostPort at = *sim::parse_host_port(options.control).value;  // checked by the option
    sim::Result<std::unique_ptr<sim::ControlServer>> opened = sim::ControlServer::open(at.host, at.port, notes);
    if (!opened) {
      std::cerr << "hmc-emu: control: " << opened.error << '\n';
      return kExitIo;
    }
    control = std::move(*opened.value);
  }
  // Printed even with --quiet: they are how a client finds the board.
  if (const std::string text = (*link.value)->announcement(); !text.empty()) {
    std::cerr << "hmc-emu: " << text << '\n';
  }
  if (control) std::cerr << "hmc-emu: control listening on " << control->address() << '\n';
  std::cerr << std::flush;
  signal(SIGINT, request_stop);
  signal(SIGTERM, request_stop);
  signal(SIGPIPE, SIG_IGN);
  if (bootloader_first) {
    const int code = run_bootloader_first(options, image);
    if (code >= 0) return code;
  }

  std::vector<sim::ScriptEvent> script;
  if (!options.script.empty()) {
    std::ifstream in(options.script);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) {
      std::cerr << "hmc-emu: cannot read script '" << options.script << "'\n";
      return kExitIo;
    }
    sim::Result<std::vector<sim::ScriptEvent>> parsed = sim::parse_script(text.str());
    if (!parsed) {
      std::cerr << "hmc-emu: " << options.script << ":" << parsed.error << '\n';
      return kExitUsage;
    }
    script = std::move(*parsed.value);
  }

  std::ofstream trace_file;
  std::unique_ptr<Trace> trace;
  if (options.trace == "-") {
    trace = std::make_unique<Trace>(std::cerr);
  } else if (!options.trace.empty()) {
    trace_file.open(options.trace, std::ios::binary | std::ios::trunc);
    if (!trace_file) {
      std::cerr << "hmc-emu: cannot write trace '" << options.trace << "'\n";
      return kExitIo;
    }
    trace = std::make_unique<Trace>(trace_file);
  }
  Emulator emulator(resolved, image, **link.value, std::move(script), control.get());
  emulator.set_trace(trace.get());
  if (!emulator.power_on(Pm::kCausePowerOn, error)) {
    std::cerr << "hmc-emu: " << error << '\n';
    return kExitImage;
  }
  const auto start = std::chrono::steady_clock::now();
  const int code = emulator.run();
  if (trace) trace->flush();
  if (options.stats) {
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Machine& m = emulator.machine();
    const double virtual_s = static_cast<double>(emulator.now_ps()) / 1e12;
    std::fprintf(stderr, "hmc-emu: %.3f s virtual in %.3f s wall (%.2fx real time), %" PRIu64
                         " cycles in %" PRIu64 " chunks\n", virtual_s, wall, virtual_s / wall,
                 m.chip->cycles(), m.cpu->chunks());
    std::fprintf(stderr, "hmc-emu: command UART: %" PRIu64 " received bytes lost to overflow\n",
                 m.chip->sercom(kUartSercom).rx_overflows());
    const auto& from = emulator.measure_start();
    const auto to = emulator.snapshot();
    const uint64_t cycles = to.cycles - from.cycles;
    std::fprintf(stderr, "hmc-emu: measured from %.6f s to %.6f s: %" PRIu64 " cycles, %" PRIu64
                         " instructions, %" PRIu64 " flash wait cycles; steps %" PRIu64 " %" PRIu64
                         " %" PRIu64 "\n",
                 static_cast<double>(from.ps) / 1e12, static_cast<double>(to.ps) / 1e12, cycles,
                 to.instructions - from.instructions, to.flash_wait_cycles - from.flash_wait_cycles,
                 to.steps[0] - from.steps[0], to.steps[1] - from.steps[1],
                 to.steps[2] - from.steps[2]);
    // STEP pulse timing per motor over the window, in ns (the DRV8711 wants ≥ 1900 high and low).
    for (unsigned motor = 0; motor < 3; ++motor) {
      const Board::Axis::Pulses& p = m.chip->board().axis(motor).pulses;
      if (p.ended == 0) continue;
      const auto ns = [](uint64_t ps) { return ps == UINT64_MAX ? -1.0 : static_cast<double>(ps) / 1000.0; };
      std::fprintf(stderr, "hmc-emu: STEP %u: %" PRIu64 " pulses, high %.1f-%.1f ns, low >= %.1f ns, "
                           "period %.1f-%.1f ns\n",
                   motor + 1, p.ended, ns(p.high_min_ps), ns(p.high_max_ps), ns(p.low_min_ps),
                   ns(p.period_min_ps), ns(p.period_max_ps));
    }
    const uint64_t thread = to.thread_cycles - from.thread_cycles;
    std::fprintf(stderr, "hmc-emu: thread mode (the main loop): %" PRIu64 " cycles (%.2f %% of the CPU)\n", thread,
                 cycles != 0 ? 100.0 * static_cast<double>(thread) / static_cast<double>(cycles) : 0.0);
    if (!options.count_calls.empty()) {
      const uint64_t calls = to.calls - from.calls;
      std::fprintf(stderr, "hmc-emu: %s: %" PRIu64 " calls, %.1f thread-mode cycles per call\n",
                   options.count_calls.c_str(), calls,
                   calls != 0 ? static_cast<double>(thread) / static_cast<double>(calls) : 0.0);
    }
    for (const auto& [exception, figures] : to.handlers) {
      Cpu::HandlerFigures before;
      if (const auto it = from.handlers.find(exception); it != from.handlers.end()) before = it->second;
      const uint64_t count = figures.count - before.count;
      const uint64_t spent = figures.cycles - before.cycles;
      if (count == 0) continue;
      std::fprintf(stderr, "hmc-emu: exception %u: %" PRIu64 " entries, %.1f cycles each, %" PRIu64
                           " cycles (%.2f %% of the CPU), %" PRIu64 " instructions, %" PRIu64
                           " flash wait cycles\n",
                   exception, count, static_cast<double>(spent) / static_cast<double>(count), spent,
                   cycles != 0 ? 100.0 * static_cast<double>(spent) / static_cast<double>(cycles) : 0.0,
                   figures.instructions - before.instructions,
                   figures.flash_wait_cycles - before.flash_wait_cycles);
    }
  }
  return code;
}

}  // namespace
}  // namespace hmc::emu

int main(int argc, char** argv) {
  const auto host_port_check = [](const std::string& text) {
    const hmc::sim::Result<hmc::sim::HostPort> at = hmc::sim::parse_host_port(text);
    return at ? std::string() : at.error;
  };
  hmc::emu::Options options;
  CLI::App app{"hmc-emu: runs the SAMD21 firmware image on an emulated board (docs/emu.md)"};
  app.add_option("image", options.image,
                 "the firmware ELF (hmc-firmware.elf) or raw image (hmc-firmware.bin, see --raw-at); with --usb-pty/--uf2-drive, what the flash holds "
                 "before flashing (default: erased)");
  app.add_option("--raw-at", options.raw_at,
                 "where an IMAGE ending in .bin (raw flash bytes, no symbols) starts: 0x2000 (hmc-firmware.bin, "
                 "behind the bootloader; the default) or 0x0 (hmc-firmware-nobl.bin)")
      ->check(CLI::IsMember({"0x2000", "0x0"}));
  CLI::Option* pty = app.add_flag("--pty", options.pty, "serve the command UART on a new pseudo-terminal (its path is printed)");
  app.add_option("--tcp", options.tcp,
                 "serve the command UART on a TCP listener at HOST:PORT (port 0: any free one; the address is "
                 "printed), one client at a time, as hmc-sim's")
      ->type_name("HOST:PORT")
      ->check(host_port_check)
      ->excludes(pty);
  app.add_option("--control", options.control,
                 "hmc-sim's control channel on a TCP listener at HOST:PORT: press/release/auto M END, estop, "
                 "estop release, fault M BITS, send TEXT, status (docs/sim.md)")
      ->type_name("HOST:PORT")
      ->check(host_port_check);
  app.add_option("--hold-input", options.hold_input_s,
                 "the host's bytes wait until this many seconds of virtual time since power-up (e.g. past the "
                 "power-up self-test); they always wait for the board's first line")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--fast", options.fast, "run virtual time unthrottled instead of in real time");
  app.add_option("--baud", options.baud, "the host side's baud rate (the image's own is 115200)")
      ->check(CLI::Range(300, 4000000));
  app.add_option("--max-time", options.max_time_s,
                 "stop after this many seconds of virtual time and say where the PC is")
      ->check(CLI::PositiveNumber);
  app.add_flag("--no-crystal", options.no_crystal, "no 32.768 kHz crystal on PA00/PA01");
  app.add_option("--bootloader", options.bootloader,
                 "start as the bootloader leaves the chip (yes), from a cold reset (no), or by the "
                 "image's link address (auto: 0x2000 yes, 0x0 no)")
      ->check(CLI::IsMember({"auto", "yes", "no"}));
  app.add_flag("--watchdog-resets", options.watchdog_resets,
               "a watchdog expiry resets the chip (default: it stops the emulator as an error)");
  app.add_flag("--run-fault-handler", options.run_fault_handler,
               "a HardFault runs the image's handler (default: it stops the emulator as an error)");
  app.add_flag("--quiet", options.quiet, "no notes on standard error");
  app.add_option("--usb-pty", options.usb_pty,
                 "start in the bootloader: the SAM-BA monitor (bossac) on a pseudo-terminal named by "
                 "this link, standing for the native USB port; the board boots what is flashed");
  app.add_option("--uf2-drive", options.uf2_drive,
                 "start in the bootloader: its UF2 drive as this directory; a .uf2 copied there is flashed "
                 "and booted");
  app.add_flag("--touch-to-enter", options.touch_to_enter,
               "with --usb-pty: the port starts as an application's and a 1200-baud touch enters the bootloader");
  app.add_option("--script", options.script,
                 "inject hmc-sim's script events (send, press, release, estop, estop release) at their "
                 "virtual times since power-up (docs/sim.md, \"Injected events\")");
  app.add_option("--axis", options.axes,
                 "switch positions and start of motor 1 or 2's axis, in 1/256 step (repeatable; as hmc-sim's)")
      ->type_name("M:LOW:HIGH:START")
      ->check([](const std::string& text) {
        const hmc::sim::Result<hmc::sim::AxisOption> axis = hmc::sim::parse_axis(text);
        return axis ? std::string() : axis.error;
      });
  app.add_option("--stall-at", options.stall_at_s,
                 "the CPU hangs at this virtual time (seconds): no instruction, no interrupt until a "
                 "reset, as a stalled main loop looks to the watchdog")
      ->check(CLI::PositiveNumber);
  app.add_option("--trace", options.trace,
                 "write what the devices on the pins see (steps, switches, servo pulses, LED colours decoded "
                 "from the strips' bitstreams, tones, booting LEDs) as hmc-sim's JSON-lines trace ('-': stderr)");
  app.add_flag("--stats", options.stats, "print virtual/wall time and cycles per handler at the end");
  app.add_option("--count-calls", options.count_calls,
                 "--stats counts this function's calls (a symbol, as written or demangled) and gives the "
                 "main loop's cycles per call")
      ->needs("--stats");
  app.add_option("--measure-from", options.measure_from_s,
                 "--stats counts cycles, handler entries and STEP edges from this virtual time (seconds) on")
      ->check(CLI::NonNegativeNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : hmc::emu::kExitUsage;
  }
  return hmc::emu::run(options);
}
