// hmc-sim's command line (sim_options.h): the option library reads the syntax, this file's
// parsers check the values, so a bad value is reported with the option it came with.
#include "sim_options.h"

#include <CLI/CLI.hpp>
#include <limits>
#include <vector>

#ifndef HMC_VERSION
#error "HMC_VERSION must be defined by the build"
#endif

namespace hmc::sim {
namespace {

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (size_t start = 0;;) {
    const size_t end = text.find(separator, start);
    parts.push_back(
        text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return parts;
    start = end + 1;
  }
}

// A decimal integer within [min, max], optionally signed.
Result<int64_t> parse_integer(std::string_view text, int64_t min, int64_t max, const char* what) {
  const std::string shown = "'" + std::string(text) + "'";
  const bool negative = !text.empty() && text.front() == '-';
  std::string_view digits = negative ? text.substr(1) : text;
  if (digits.empty() || digits.size() > 18 ||
      digits.find_first_not_of("0123456789") != std::string_view::npos) {
    return Result<int64_t>::fail(std::string(what) + " " + shown + " is not a whole number");
  }
  int64_t value = 0;
  for (const char c : digits) value = value * 10 + (c - '0');
  if (negative) value = -value;
  if (value < min || value > max) {
    return Result<int64_t>::fail(std::string(what) + " " + shown + " is outside " +
                                 std::to_string(min) + "-" + std::to_string(max));
  }
  return Result<int64_t>::ok(value);
}

// An option check: "" when `parse` accepts the value, else its message.
template <typename T>
std::function<std::string(const std::string&)> checked_by(Result<T> (*parse)(std::string_view)) {
  return [parse](const std::string& value) {
    Result<T> parsed = parse(value);
    return parsed ? std::string() : parsed.error;
  };
}

constexpr int64_t kPositionMin = std::numeric_limits<int32_t>::min();
constexpr int64_t kPositionMax = std::numeric_limits<int32_t>::max();

}  // namespace

Result<HostPort> parse_host_port(std::string_view text) {
  std::string_view host;
  std::string_view port;
  if (!text.empty() && text.front() == '[') {
    const size_t close = text.find("]:");
    if (close == std::string_view::npos) {
      return Result<HostPort>::fail("'" + std::string(text) + "': expected [HOST]:PORT");
    }
    host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else {
    const size_t colon = text.rfind(':');
    if (colon == std::string_view::npos) {
      return Result<HostPort>::fail("'" + std::string(text) + "': expected HOST:PORT");
    }
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  if (host.empty()) {
    return Result<HostPort>::fail("'" + std::string(text) + "': the host is missing");
  }
  Result<int64_t> number = parse_integer(port, 0, 65535, "port");
  if (!number) return Result<HostPort>::fail(number.error);
  return Result<HostPort>::ok(HostPort{std::string(host), static_cast<uint16_t>(*number.value)});
}

Result<AccelOption> parse_accel(std::string_view text) {
  const std::vector<std::string_view> parts = split(text, ':');
  if (parts.size() != 2) {
    return Result<AccelOption>::fail("'" + std::string(text) + "': expected M:A");
  }
  Result<int64_t> motor = parse_integer(parts[0], 1, proto::kMotorCount, "motor");
  if (!motor) return Result<AccelOption>::fail(motor.error);
  Result<int64_t> accel =
      parse_integer(parts[1], 0, std::numeric_limits<uint32_t>::max(), "acceleration");
  if (!accel) return Result<AccelOption>::fail(accel.error);
  return Result<AccelOption>::ok(
      AccelOption{static_cast<uint8_t>(*motor.value), static_cast<uint32_t>(*accel.value)});
}

Result<AxisOption> parse_axis(std::string_view text) {
  const std::vector<std::string_view> parts = split(text, ':');
  if (parts.size() != 4) {
    return Result<AxisOption>::fail("'" + std::string(text) + "': expected M:LOW:HIGH:START");
  }
  Result<int64_t> motor = parse_integer(parts[0], 1, 2, "motor (only 1 and 2 have switches)");
  if (!motor) return Result<AxisOption>::fail(motor.error);
  int32_t values[3] = {};
  const char* names[3] = {"LOW", "HIGH", "START"};
  for (size_t i = 0; i < 3; ++i) {
    Result<int64_t> value = parse_integer(parts[i + 1], kPositionMin, kPositionMax, names[i]);
    if (!value) return Result<AxisOption>::fail(value.error);
    values[i] = static_cast<int32_t>(*value.value);
  }
  if (values[0] >= values[1]) {
    return Result<AxisOption>::fail("'" + std::string(text) + "': LOW must be below HIGH");
  }
  AxisOption option;
  option.motor = static_cast<uint8_t>(*motor.value);
  option.axis = AxisConfig{true, values[2], values[0], values[1]};
  return Result<AxisOption>::ok(option);
}

ParsedArgs parse_args(int argc, const char* const* argv) {
  CLI::App app{
      "hmc-sim: the Hybrid Motor Controller's firmware on a simulated board, serving its "
      "serial protocol",
      "hmc-sim"};
  app.set_version_flag("--version", std::string("hmc-sim ") + HMC_VERSION);
  app.footer(
      "Examples:\n"
      "  printf 'STX#3#SVM#1#10#11#ETX\\n' | hmc-sim --fast --no-self-test\n"
      "  hmc-sim --tcp 127.0.0.1:4000                 # then connect to it as to the board\n"
      "  hmc-sim --pty --control 127.0.0.1:4001       # a serial device, switches by command\n"
      "  hmc-sim --fast --script estop.txt --trace run.jsonl --exit-when-idle < /dev/null\n"
      "\n"
      "Exit codes: 0 ok, 2 usage error or bad script, 3 file, port or terminal error.\n"
      "See docs/sim.md.");

  SimOptions options;
  options.config.baud = 115200;
  std::string tcp;
  std::string control;
  bool pty = false;
  bool legacy = false;
  bool no_replies = false;
  bool seed = false;
  bool no_self_test = false;
  std::string reset_cause = "power_on";
  std::vector<std::string> accels;
  std::vector<std::string> axes;

  CLI::Option* tcp_option =
      app.add_option(
             "--tcp", tcp,
             "Serve the link on a TCP listener, one client at a time (port 0: any free port)")
          ->type_name("HOST:PORT")
          ->check(checked_by(parse_host_port));
  app.add_flag("--pty", pty, "Serve the link on a new pseudo-terminal")->excludes(tcp_option);
  app.add_flag("--fast", options.fast,
               "Run virtual time as fast as possible instead of with the wall clock");
  app.add_option("--baud", options.config.baud,
                 "Pace received bytes at this baud rate (0: at once)")
      ->capture_default_str();
  app.add_flag("--legacy", legacy,
               "Seed rule [5]: servo and LED frames refused while a stepper runs");
  app.add_flag("--no-replies", no_replies, "Answer nothing, as the seed firmware");
  app.add_flag("--seed", seed, "Behave as the seed firmware: --legacy --no-replies");
  app.add_flag("--no-self-test", no_self_test, "Skip the steppers' self-test at power-up");
  app.add_option("--reset-cause", reset_cause,
                 "The reset cause the boot event reports: power_on, brown_out, external, watchdog or software")
      ->check(CLI::IsMember({"power_on", "brown_out", "external", "watchdog", "software"}))
      ->capture_default_str();
  app.add_option("--accel", accels, "Acceleration of motor M in steps/s² (repeatable)")
      ->type_name("M:A")
      ->check(checked_by(parse_accel));
  app.add_option("--axis", axes,
                 "Switch positions and start of motor 1 or 2, in 1/256 step (repeatable)")
      ->type_name("M:LOW:HIGH:START")
      ->check(checked_by(parse_axis));
  app.add_option("--trace", options.trace,
                 "Write every board event as JSON lines to FILE ('-': standard error)")
      ->type_name("FILE");
  app.add_option("--script", options.script, "Inject the events of FILE at their times")
      ->type_name("FILE");
  app.add_option("--control", control, "Take injected-event commands on a TCP listener")
      ->type_name("HOST:PORT")
      ->check(checked_by(parse_host_port));
  app.add_flag("--exit-when-idle", options.exit_when_idle,
               "Exit once the script is done, nobody is on the link and the board is idle");
  app.add_flag("--quiet", options.quiet, "Print only addresses and errors on standard error");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return ParsedArgs{std::nullopt, code == 0 ? kExitOk : kExitUsage};
  }

  if (!tcp.empty()) {
    options.link = LinkKind::kTcp;
    options.tcp = *parse_host_port(tcp).value;
  } else if (pty) {
    options.link = LinkKind::kPty;
  }
  if (!control.empty()) options.control = *parse_host_port(control).value;
  options.config.options.legacy = legacy || seed;
  options.config.options.replies = !(no_replies || seed);
  options.config.options.self_test = !no_self_test;
  for (uint32_t cause = 0; cause < proto::kResetCauseCount; ++cause) {
    if (reset_cause == proto::kResetCauseNames[cause]) {
      options.config.reset_cause = static_cast<proto::ResetCause>(cause);
    }
  }
  for (const std::string& text : accels) {
    const AccelOption accel = *parse_accel(text).value;
    options.config.accel[accel.motor - 1u] = accel.steps_per_s2;
  }
  for (const std::string& text : axes) {
    const AxisOption axis = *parse_axis(text).value;
    options.config.axes[axis.motor - 1u] = axis.axis;
  }
  return ParsedArgs{std::move(options), kExitOk};
}

}  // namespace hmc::sim
