// hmc-sim's text parsers: injected-event commands, times, scripts, option values and the
// command line; and what commands do to a board.
#include "sim_script.h"

#include <catch2/catch.hpp>
#include <iostream>
#include <sstream>

#include "sim_io.h"
#include "sim_options.h"

using namespace hmc::sim;

namespace {

SimCommand switch_command(Action action, uint8_t motor, uint8_t end) {
  SimCommand c;
  c.action = action;
  c.motor = motor;
  c.end = end;
  return c;
}

// The error of a parse expected to fail, or a note that it did not.
template <typename T>
std::string error_of(const Result<T>& result) {
  return result ? std::string("(accepted)") : result.error;
}

// The command line's verdict; its messages are kept off the test's output.
ParsedArgs parse(std::vector<const char*> args) {
  args.insert(args.begin(), "hmc-sim");
  std::ostringstream messages;
  std::streambuf* const cout = std::cout.rdbuf(messages.rdbuf());
  std::streambuf* const cerr = std::cerr.rdbuf(messages.rdbuf());
  ParsedArgs parsed = parse_args(static_cast<int>(args.size()), args.data());
  std::cout.rdbuf(cout);
  std::cerr.rdbuf(cerr);
  return parsed;
}

}  // namespace

TEST_CASE("switch commands name a motor with switches and an end") {
  CHECK(*parse_command("press 1 0").value == switch_command(Action::kPress, 1, 0));
  CHECK(*parse_command("  release\t2 1  ").value == switch_command(Action::kRelease, 2, 1));
  CHECK(*parse_command("auto 2 0").value == switch_command(Action::kAuto, 2, 0));
  CHECK(error_of(parse_command("press 3 0")) ==
        "motor '3': only motors 1 and 2 have limit switches");
  CHECK(error_of(parse_command("press 1 2")) == "switch end '2': expected 0 or 1");
  CHECK(error_of(parse_command("press 1")) == "press needs a motor and a switch end: press M END");
  CHECK(error_of(parse_command("release 1 1 now")) == "unexpected 'now' after release 1 1");
}

TEST_CASE("estop, status and unknown words") {
  CHECK(parse_command("estop").value->action == Action::kEstop);
  CHECK(parse_command(" estop  release ").value->action == Action::kEstopRelease);
  CHECK(error_of(parse_command("estop now")) == "estop takes nothing or 'release', got 'now'");
  CHECK(parse_command("status").value->action == Action::kStatus);
  const Result<SimCommand> fault = parse_command("fault 2 6");
  REQUIRE(fault);
  CHECK(fault.value->action == Action::kFault);
  CHECK((fault.value->motor == 2 && fault.value->end == 6));
  CHECK(error_of(parse_command("fault 4 1")) == "fault: motor '4' is not 1, 2 or 3");
  CHECK(error_of(parse_command("fault 1 256")) == "fault: expected STATUS bits 0-255 after the motor, got '1 256'");
  CHECK(error_of(parse_command("status 1")) == "status takes no arguments");
  CHECK(error_of(parse_command("")) == "no command");
  CHECK(error_of(parse_command("jump 1")) ==
        "unknown command 'jump' (expected press, release, auto, estop, fault, send or status)");
  CHECK(error_of(parse_command("Press 1 0")).rfind("unknown command 'Press'", 0) == 0);
}

TEST_CASE("send keeps its text verbatim after one blank") {
  CHECK(parse_command("send STX#3#SVM#1#10#11#ETX").value->text == "STX#3#SVM#1#10#11#ETX");
  CHECK(parse_command("send   STX#1 ").value->text == "  STX#1 ");
  CHECK(parse_command("send").value->text.empty());
  CHECK(parse_command("send").value->action == Action::kSend);
}

TEST_CASE("times in seconds, milliseconds, microseconds and ticks") {
  CHECK(*parse_time("1.5s").value == 72000000u);
  CHECK(*parse_time("250ms").value == 12000000u);
  CHECK(*parse_time("100us").value == 4800u);
  CHECK(*parse_time("123t").value == 123u);
  CHECK(*parse_time("0s").value == 0u);
  CHECK(*parse_time("0.001ms").value == 48u);
}

TEST_CASE("bad times say what is wrong") {
  CHECK(error_of(parse_time("1.5")) ==
        "time '1.5': expected a number and a unit s, ms, us or t (ticks)");
  CHECK(error_of(parse_time("s")) ==
        "time 's': expected a number and a unit s, ms, us or t (ticks)");
  CHECK(error_of(parse_time("1,5s")) == "time '1,5s': '1,5' is not a decimal number");
  CHECK(error_of(parse_time("2.s")) == "time '2.s': '2.' is not a decimal number");
  CHECK(error_of(parse_time("-1s")) == "time '-1s': '-1' is not a decimal number");
  CHECK(error_of(parse_time("1.5t")) == "time '1.5t': ticks are whole numbers");
  CHECK(error_of(parse_time("0.01us")) ==
        "time '0.01us' is not a whole number of ticks (48 per us)");
  CHECK(error_of(parse_time("0.1234567891s")) ==
        "time '0.1234567891s': at most 9 digits after the point");
  CHECK(error_of(parse_time("99999999999999999999s")) ==
        "time '99999999999999999999s' is too large");
  CHECK(error_of(parse_time("999999999999s")) == "time '999999999999s' is too large");
}

TEST_CASE("a script: comments, blanks, events in time order") {
  const Result<std::vector<ScriptEvent>> script = parse_script(
      "# a comment\n"
      "\n"
      "at 2s estop release\r\n"
      "   # indented comment\n"
      "at 1s estop\n"
      "at 1s send STX#3#SVM#1#10#11#ETX\n"
      "at 5t press 1 1");
  REQUIRE(script);
  const std::vector<ScriptEvent>& events = *script.value;
  REQUIRE(events.size() == 4);
  CHECK(events[0].at == 5u);
  CHECK(events[0].line == 7u);
  CHECK(events[1].command.action == Action::kEstop);  // equal times keep their file order
  CHECK(events[2].command.text == "STX#3#SVM#1#10#11#ETX");
  CHECK(events[3].command.action == Action::kEstopRelease);
  CHECK(events[3].line == 3u);
}

TEST_CASE("a bad script line is reported with its number") {
  CHECK(error_of(parse_script("at 1s estop\nestop\n")) == "2: expected 'at TIME COMMAND'");
  CHECK(error_of(parse_script("at\n")) == "1: expected a time after 'at'");
  CHECK(error_of(parse_script("at 1s\n")) == "1: expected a command after the time");
  CHECK(error_of(parse_script("\n\nat 1x press 1 0\n")) ==
        "3: time '1x': expected a number and a unit s, ms, us or t (ticks)");
  CHECK(error_of(parse_script("at 1s press 4 0\n")) ==
        "1: motor '4': only motors 1 and 2 have limit switches");
  CHECK(error_of(parse_script("at 1s status\n")) == "1: status is for the control channel only");
  CHECK(parse_script("").value->empty());
}

TEST_CASE("HOST:PORT values") {
  CHECK(parse_host_port("127.0.0.1:4000").value->host == "127.0.0.1");
  CHECK(parse_host_port("127.0.0.1:4000").value->port == 4000);
  CHECK(parse_host_port("localhost:0").value->port == 0);
  CHECK(parse_host_port("[::1]:65535").value->host == "::1");
  CHECK(error_of(parse_host_port("4000")) == "'4000': expected HOST:PORT");
  CHECK(error_of(parse_host_port(":4000")) == "':4000': the host is missing");
  CHECK(error_of(parse_host_port("h:65536")) == "port '65536' is outside 0-65535");
  CHECK(error_of(parse_host_port("h:x")) == "port 'x' is not a whole number");
  CHECK(error_of(parse_host_port("[::1]4000")) == "'[::1]4000': expected [HOST]:PORT");
}

TEST_CASE("--accel and --axis values") {
  CHECK(parse_accel("3:20000").value->motor == 3);
  CHECK(parse_accel("3:20000").value->steps_per_s2 == 20000u);
  CHECK(error_of(parse_accel("4:100")) == "motor '4' is outside 1-3");
  CHECK(error_of(parse_accel("1:-5")) == "acceleration '-5' is outside 0-4294967295");
  CHECK(error_of(parse_accel("1")) == "'1': expected M:A");

  const Result<AxisOption> axis = parse_axis("2:-100:5000:-50");
  REQUIRE(axis);
  CHECK(axis.value->motor == 2);
  CHECK(axis.value->axis.has_switches);
  CHECK(axis.value->axis.low_switch == -100);
  CHECK(axis.value->axis.high_switch == 5000);
  CHECK(axis.value->axis.start == -50);
  CHECK(error_of(parse_axis("3:0:1:0")) == "motor (only 1 and 2 have switches) '3' is outside 1-2");
  CHECK(error_of(parse_axis("1:10:10:0")) == "'1:10:10:0': LOW must be below HIGH");
  CHECK(error_of(parse_axis("1:0:3000000000:0")) ==
        "HIGH '3000000000' is outside -2147483648-2147483647");
  CHECK(error_of(parse_axis("1:0:1")) == "'1:0:1': expected M:LOW:HIGH:START");
}

TEST_CASE("the command line maps onto the board's configuration") {
  const ParsedArgs defaults = parse({});
  REQUIRE(defaults.options);
  CHECK(defaults.options->link == LinkKind::kStdio);
  CHECK(defaults.options->config.baud == 115200u);
  CHECK(defaults.options->config.options.replies);
  CHECK(defaults.options->config.options.self_test);
  CHECK_FALSE(defaults.options->config.options.legacy);

  const ParsedArgs seed = parse({"--seed", "--no-self-test", "--baud", "0", "--fast"});
  REQUIRE(seed.options);
  CHECK(seed.options->config.options.legacy);
  CHECK_FALSE(seed.options->config.options.replies);
  CHECK_FALSE(seed.options->config.options.self_test);
  CHECK(seed.options->config.baud == 0u);
  CHECK(seed.options->fast);

  const ParsedArgs full =
      parse({"--tcp", "127.0.0.1:0", "--control", "localhost:7", "--accel", "1:100", "--accel",
             "3:300", "--axis", "2:0:1000:500", "--exit-when-idle"});
  REQUIRE(full.options);
  CHECK(full.options->link == LinkKind::kTcp);
  CHECK(full.options->tcp.host == "127.0.0.1");
  CHECK(full.options->control->port == 7);
  CHECK(full.options->config.accel == std::array<uint32_t, 3>{100, 0, 300});
  CHECK(full.options->config.axes[1].high_switch == 1000);
  CHECK(full.options->config.axes[0].high_switch == 409600);  // untouched
  CHECK(full.options->exit_when_idle);

  CHECK(parse({"--pty"}).options->link == LinkKind::kPty);
}

TEST_CASE("bad command lines exit 2") {
  CHECK(parse({"--tcp", "x:1", "--pty"}).exit_code == kExitUsage);
  CHECK(parse({"--accel", "4:100"}).exit_code == kExitUsage);
  CHECK(parse({"--axis", "1:5:3:0"}).exit_code == kExitUsage);
  CHECK(parse({"--tcp", "nohost"}).exit_code == kExitUsage);
  CHECK(parse({"--baud", "-1"}).exit_code == kExitUsage);
  CHECK(parse({"--frobnicate"}).exit_code == kExitUsage);
  CHECK_FALSE(parse({"--frobnicate"}).options);
}

TEST_CASE("control lines are split at LF, CR dropped, overlong lines cut") {
  LineSplitter splitter;
  CHECK(splitter.feed("sta").empty());
  CHECK(splitter.feed("tus\r\nestop\npre") == std::vector<std::string>{"status", "estop"});
  CHECK(splitter.feed("ss 1 0\n\n") == std::vector<std::string>{"press 1 0", ""});
  const std::vector<std::string> cut =
      splitter.feed(std::string(LineSplitter::kMaxLine + 10, 'x') + "\nok\n");
  REQUIRE(cut.size() == 2);
  CHECK(cut[0].size() == LineSplitter::kMaxLine);
  CHECK(cut[1] == "ok");
}

TEST_CASE("commands act on the board; status reports it") {
  SimConfig config;
  config.options.self_test = false;
  SimBoard board(config);
  board.boot();
  board.run_for(hmc::hal::kTicksPerSecond / 100);

  apply_command(board, *parse_command("press 1 1").value);
  CHECK(board.limit_pressed(1, 1));
  apply_command(board, *parse_command("release 1 1").value);
  CHECK_FALSE(board.limit_pressed(1, 1));
  apply_command(board, *parse_command("press 2 0").value);
  apply_command(board, *parse_command("auto 2 0").value);
  CHECK_FALSE(board.limit_pressed(2, 0));  // mid-travel: open on its own

  apply_command(board, *parse_command("estop").value);
  CHECK(board.emergency_pressed());
  apply_command(board, *parse_command("estop release").value);
  CHECK_FALSE(board.emergency_pressed());

  board.take_output();  // the boot event and the switch events so far
  apply_command(board, *parse_command("press 1 0").value);
  apply_command(board, *parse_command("send STX#6#LED#1#200#120#100#20#185#ETX").value);
  board.run_for(hmc::hal::kTicksPerSecond / 10);
  CHECK(board.take_output() == "STX#4#EVL#1#0#1#2#ETX\nSTX#1#ACK#0#ETX\n");

  const std::string status = status_json(board);
  CHECK(status.rfind("{\"t\":", 0) == 0);
  CHECK(status.find("\"emergency\":false") != std::string::npos);
  CHECK(
      status.find("{\"motor\":1,\"pos\":204800,\"fw_pos\":0,\"steps\":0,\"state\":\"idle\","
                  "\"homed\":false,\"switches\":[true,false],\"microstep\":16,\"enabled\":true}") !=
      std::string::npos);
  CHECK(status.find("\"switches\":null") != std::string::npos);
  CHECK(status.find("{\"strip\":1,\"r\":200,\"g\":120,\"b\":100,\"w\":20}") != std::string::npos);
  CHECK(status.find("{\"servo\":1,\"pulse_us\":1472}") != std::string::npos);
  CHECK(status.back() == '}');
}
