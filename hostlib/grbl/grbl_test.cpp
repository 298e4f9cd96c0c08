// The grbl front end against the simulated board (sim://, fast time): what a sender reads back,
// and what the board did, counted in its trace (every STEP edge, servo pulse and LED colour).
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include "hmc/grbl.h"
#include "hmc/sim_transport.h"

using namespace hmc;
using namespace hmc::grbl;

namespace {

struct Rig {
  std::filesystem::path dir;
  std::string trace;
  std::unique_ptr<Session> session;
  std::unique_ptr<FrontEnd> front;
  std::optional<Profile> profile;
  std::string seen;  // everything the sender was sent

  explicit Rig(const std::string& profile_text = "") {
    static int counter = 0;
    dir = std::filesystem::temp_directory_path() / ("hmc-grbl-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    ::setenv("HMC_SIM_STATE", dir.c_str(), 1);
    trace = (dir / "trace.jsonl").string();
    auto port = open_sim_port("sim://grbl?fast&fresh&nosave&trace=" + trace, {});
    REQUIRE(port.ok());
    auto s = Session::open(std::move(port.value()), {});
    if (!s) FAIL(s.error().message);
    session = std::move(s.value());
    if (!profile_text.empty()) {
      auto p = parse_profile(profile_text, "test.toml");
      if (!p) FAIL(p.error().text());
      profile = *p;
    }
    auto axes = map_axes(profile ? &*profile : nullptr);
    REQUIRE(axes.ok());
    front = std::make_unique<FrontEnd>(*session, *axes);
    front->connected();
    seen += front->take_output();
  }
  ~Rig() { std::filesystem::remove_all(dir); }

  // Sends bytes and services until `until` appears in the output after them (by default the
  // line's answer: ok or error:N), for at most 20000 rounds.
  std::string talk(const std::string& bytes, const std::string& until = "") {
    front->receive(bytes);
    std::string got;
    const auto done = [&] {
      if (!until.empty()) return got.find(until) != std::string::npos;
      return got.find("ok\r\n") != std::string::npos || std::regex_search(got, std::regex("error:\\d+\r\n"));
    };
    for (int i = 0; i < 20000 && !done(); ++i) {
      auto served = front->service();
      if (!served) FAIL(served.error().message);
      got += front->take_output();
    }
    seen += got;
    return got;
  }
  void settle() {
    for (int i = 0; i < 20000 && (front->state() != State::kIdle || session->model().any_moving()); ++i) {
      REQUIRE(front->service().ok());
      seen += front->take_output();
    }
  }
  // STEP edges per motor, net in the direction they went (from the trace's positions).
  std::map<int, std::pair<long, long>> steps() const {  // motor -> (edges, last t)
    std::map<int, std::pair<long, long>> out;
    std::ifstream in(trace);
    std::string line;
    const std::regex step(R"re("t":(\d+),"ev":"step","motor":(\d))re");
    std::smatch m;
    while (std::getline(in, line)) {
      if (std::regex_search(line, m, step)) {
        auto& e = out[std::stoi(m[2])];
        ++e.first;
        e.second = std::stol(m[1]);
      }
    }
    return out;
  }
};

const char* kGantry = R"(
[axis.x]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
limits = ["0mm", "100mm"]
speed = "50mm/s"
accel = "500mm/s2"
[axis.x.homing]
end = "reverse"
seek_speed = "100mm/s"
[axis.y]
motor = 2
mm_per_rev = "40mm"
speed = "50mm/s"
accel = "500mm/s2"
)";

}  // namespace

TEST_CASE("banner, $I, $$, $G, $# and the status report") {
  Rig rig;
  CHECK(rig.seen == "\r\nGrbl 1.1h ['$' for help]\r\n");
  CHECK(rig.talk("$I\n").find("[VER:1.1h.hmc:]\r\n[OPT:V,16,128]\r\n") != std::string::npos);
  const std::string settings = rig.talk("$$\n");
  CHECK(settings.find("$100=80.000\r\n") != std::string::npos);
  CHECK(settings.find("$110=2400.000\r\n") != std::string::npos);  // 3200 steps/s at 80 steps/mm
  CHECK(rig.talk("$G\n") == "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
  CHECK(rig.talk("$#\n").find("[G54:0.000,0.000,0.000]\r\n") != std::string::npos);
  CHECK(rig.talk("?", ">\r\n") == "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n");
}

TEST_CASE("G1 on two axes: exact steps, arriving together") {
  Rig rig;
  CHECK(rig.talk("G1 X10 Y5 F600\n") == "ok\r\n");
  rig.settle();
  auto steps = rig.steps();
  CHECK(steps[1].first == 800);  // 10 mm at 80 steps/mm
  CHECK(steps[2].first == 400);
  // Each axis follows its share of one profile: the last steps come within a few ms of each other
  // (the second STM line starts ~3 ms later at 115200 baud).
  const double skew_ms = static_cast<double>(std::abs(steps[1].second - steps[2].second)) / 48000.0;
  CHECK(skew_ms < 6);
  CHECK(rig.talk("?", ">\r\n").find("<Idle|MPos:10.000,5.000,0.000|") == 0);
  CHECK(rig.talk("G91 G0 X-2.5\n") == "ok\r\n");
  rig.settle();
  CHECK(rig.steps()[1].first == 1000);
  CHECK(rig.talk("?", ">\r\n").find("<Idle|MPos:7.500,5.000,0.000|") == 0);
}

TEST_CASE("an arc, a servo and an LED reach the board") {
  Rig rig;
  CHECK(rig.talk("G1 X10 F1200\n") == "ok\r\n");
  CHECK(rig.talk("G3 X0 Y10 I-10 J0\n") == "ok\r\n");
  CHECK(rig.talk("M280 P0 S135\n") == "ok\r\n");
  CHECK(rig.talk("M150 S1 R255 U128 B0 W0\n") == "ok\r\n");
  rig.settle();
  CHECK(rig.session->model().board.servo1_us == proto::servo_pulse_us(135));
  CHECK(rig.session->model().strips[1].r == 255);
  CHECK(rig.session->model().strips[1].g == 128);
  const std::string status = rig.talk("?", ">\r\n");
  CHECK(status.find("MPos:0.000,10.000,0.000") != std::string::npos);
  std::ifstream in(rig.trace);
  const std::string trace((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(trace.find(R"("ev":"led","strip":2,"r":255,"g":128,"b":0,"w":0)") != std::string::npos);
}

TEST_CASE("bad lines: grbl's errors with a message, and nothing moves") {
  Rig rig;
  CHECK(rig.talk("G1 X10\n") == "[MSG:G1 needs a feed rate: give F]\r\nerror:22\r\n");
  CHECK(rig.talk("M3 S1000\n").find("error:20\r\n") != std::string::npos);
  CHECK(rig.talk("G0 A5\n") == "[MSG:A5: the board has no such word or axis (only X, Y, Z)]\r\nerror:20\r\n");
  CHECK(rig.talk("G0 X1..2\n").find("error:") != std::string::npos);
  CHECK(rig.talk(std::string(81, 'X') + "\n").find("error:11\r\n") != std::string::npos);
  CHECK(rig.talk("G0 X\x01\x02\xff" "5\n").find("error:1\r\n") != std::string::npos);
  CHECK(rig.talk("$99=1\n").find("error:3\r\n") != std::string::npos);
  CHECK(rig.talk("$100=-1\n").find("error:4\r\n") != std::string::npos);
  CHECK(rig.talk("$H\n").find("error:5\r\n") != std::string::npos);  // no axis homes
  CHECK(rig.talk("\n") == "ok\r\n");
  CHECK(rig.talk("G4 P0.1\r\n") == "ok\r\n");  // CRLF ends one line: one answer
  CHECK(rig.talk("?", ">\r\n").find("ok") == std::string::npos);
  rig.settle();
  CHECK(rig.steps().empty());
}

TEST_CASE("$N= changes the running front end: steps per mm, arc tolerance") {
  Rig rig;
  CHECK(rig.talk("$100=160\n") == "[MSG:$100 changed for this hmc grbl only: the profile file is not written]\r\nok\r\n");
  CHECK(rig.talk("G0 X1\n") == "ok\r\n");
  rig.settle();
  CHECK(rig.steps()[1].first == 160);
  CHECK(rig.talk("$$\n").find("$100=160.000\r\n") != std::string::npos);
  CHECK(rig.talk("$12=0.5\n").find("ok\r\n") != std::string::npos);
  CHECK(rig.front->interpreter().settings().arc_tolerance_mm == 0.5);
  CHECK(rig.talk("$0=5\n").find("fixed by the board") != std::string::npos);
}

TEST_CASE("homing, soft limits and jogging") {
  Rig rig(kGantry);
  CHECK(rig.seen.find("[MSG:'$H'|'$X' to unlock]") != std::string::npos);  // X homes and is not homed
  CHECK(rig.talk("G0 X1\n").find("error:9\r\n") != std::string::npos);
  CHECK(rig.talk("$H\n") == "ok\r\n");
  CHECK(rig.session->model().motor(1).homed);
  CHECK(rig.talk("?", ">\r\n").find("<Idle|MPos:0.000,") == 0);
  const std::string beyond = rig.talk("G0 X150\n", "error:9\r\n");
  CHECK(beyond.find("ALARM:2\r\n") != std::string::npos);
  CHECK(beyond.find("beyond its soft limits, 0.000 to 100.000 mm") != std::string::npos);
  CHECK(rig.talk("$X\n") == "[MSG:Caution: Unlocked]\r\nok\r\n");
  CHECK(rig.talk("$J=G91 X150 F600\n").find("error:15\r\n") != std::string::npos);
  CHECK(rig.talk("$J=G91 X5 F600\n") == "ok\r\n");
  rig.settle();
  CHECK(rig.talk("?", ">\r\n").find("<Idle|MPos:5.000,") == 0);
  CHECK(rig.front->interpreter().modal().incremental == false);
}

TEST_CASE("feed hold, resume, soft reset and a sender that goes away") {
  Rig rig;
  CHECK(rig.talk("G1 X100 F1200\n") == "ok\r\n");
  rig.talk("?", "<Run|");
  rig.front->receive("!");
  for (int i = 0; i < 20000 && rig.front->state() != State::kHold; ++i) REQUIRE(rig.front->service().ok());
  std::string held;
  for (int i = 0; i < 200 && held.find("Hold:0") == std::string::npos; ++i) held = rig.talk("?", ">\r\n");
  CHECK(held.find("<Hold:0|") == 0);
  const long at_hold = rig.steps()[1].first;
  CHECK(at_hold > 0);
  CHECK(at_hold < 8000);
  rig.front->receive("~");
  rig.settle();
  CHECK(rig.steps()[1].first == 8000);  // resumed to the exact end

  CHECK(rig.talk("G1 X0 F1200\n") == "ok\r\n");
  rig.talk("?", "<Run|");
  const std::string reset = rig.talk("\x18", "for help]\r\n");
  CHECK(reset.find("ALARM:3\r\n") != std::string::npos);
  CHECK_FALSE(rig.session->model().any_moving());
  CHECK(rig.front->state() == State::kAlarm);
  CHECK(rig.talk("$X\n").find("ok\r\n") != std::string::npos);

  CHECK(rig.talk("G1 X100 F1200\n") == "ok\r\n");
  rig.talk("?", "<Run|");
  REQUIRE(rig.front->sender_gone().ok());
  CHECK_FALSE(rig.session->model().any_moving());
  const long stopped_at = rig.steps()[1].first;
  for (int i = 0; i < 100; ++i) REQUIRE(rig.front->service().ok());
  CHECK(rig.steps()[1].first == stopped_at);  // nothing moves on
  rig.front->connected();
  CHECK(rig.front->take_output().find("went away during a motion") != std::string::npos);
}

TEST_CASE("random lines: each gets exactly one ok or error, in order, and hmc grbl goes on") {
  Rig rig;
  const std::string alphabet = "GMFIJKLNRSTUBWA0123456789.-+ ()$=;%\t\x01\x7f\x80\xff";
  uint32_t seed = 777;
  const auto next = [&seed] {
    seed = seed * 1103515245u + 12345u;
    return (seed >> 16) & 0x7fffu;
  };
  std::string input;
  const size_t lines = 400;
  for (size_t i = 0; i < lines; ++i) {
    const size_t length = next() % 30;
    for (size_t k = 0; k < length; ++k) input.push_back(alphabet[next() % alphabet.size()]);
    input.push_back('\n');
  }
  rig.front->receive(input);
  std::string got;
  const std::regex answer("(^|\n)(ok|error:\\d+)\r");
  size_t answers = 0;
  for (int i = 0; i < 20000 && answers < lines; ++i) {
    if (i % 50 == 49) rig.front->receive("~");  // past any M0
    REQUIRE(rig.front->service().ok());
    got += rig.front->take_output();
    answers = static_cast<size_t>(std::distance(std::sregex_iterator(got.begin(), got.end(), answer), std::sregex_iterator()));
  }
  CHECK(answers == lines);
  CHECK(got.find("ALARM") == std::string::npos);
  CHECK(rig.talk("$X\n").find("ok\r\n") != std::string::npos);
  CHECK(rig.talk("G0 X1\n") == "ok\r\n");
}
