// The C++ side of `scripts/bench python`: the two calls the Python module is timed on, made
// from C++ through libhmc directly — an encode + decode round trip of one STM frame, and a full
// status read (Session::refresh: STA for every unit) on a board — so the module's overhead shows
// as the difference. Prints the median of each in microseconds.
//
//   binding_bench [--port PORT] [--count N]    (default sim://bench-cpp?fast&fresh&nosave)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hmc/codec.h"
#include "hmc/session.h"
#include "hmc/transport.h"

namespace {

using Clock = std::chrono::steady_clock;

template <typename Act>
double median_us(int count, Act act) {
  std::vector<double> times;
  times.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    const Clock::time_point start = Clock::now();
    act();
    times.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::string port = "sim://bench-cpp?fast&fresh&nosave";
  int count = 2000;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--port" && i + 1 < argc) {
      port = argv[++i];
    } else if (arg == "--count" && i + 1 < argc) {
      count = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: binding_bench [--port PORT] [--count N]\n");
      return 2;
    }
  }
  const hmc::Command move = hmc::StepperMove{1, hmc::proto::kActionForward, 128, 1000, 500};
  size_t checked = 0;
  const double codec = median_us(count * 10, [&] {
    const std::string frame = hmc::encode(move).value();
    checked += hmc::decode(frame)->command == move ? 1u : 0u;
  });
  if (checked != static_cast<size_t>(count) * 10) {
    std::fprintf(stderr, "binding_bench: a round trip changed the command\n");
    return 1;
  }
  auto link = hmc::open_port(port);
  if (!link) {
    std::fprintf(stderr, "binding_bench: %s\n", link.error().message.c_str());
    return 3;
  }
  auto session = hmc::Session::open(std::move(*link), {});
  if (!session) {
    std::fprintf(stderr, "binding_bench: %s\n", session.error().message.c_str());
    return 4;
  }
  bool ok = true;
  const double status = median_us(count / 10 + 1, [&] { ok = ok && session.value()->refresh().ok(); });
  if (!ok) {
    std::fprintf(stderr, "binding_bench: a status read failed\n");
    return 4;
  }
  std::printf("encode+decode %.3f us\nstatus %.1f us\n", codec, status);
  return 0;
}
