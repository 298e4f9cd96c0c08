// Round trip of one command through a session: the time from writing a line to having its reply,
// median of N, beside the time the two frames take on the wire at 115200 baud (10 bits a byte).
//
// scripts/bench rtt runs it against hmc-sim over TCP twice, side by side: the bytes delivered at
// once, and paced at 115200 baud as on the real link, so the host's and simulator's own cost
// shows as the difference.
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

double wire_ms(size_t bytes, double baud) { return static_cast<double>(bytes) * 10.0 / baud * 1000.0; }

}  // namespace

int main(int argc, char** argv) {
  std::string port;
  int count = 1000;
  bool paced = false;  // the board behind the port receives and sends at 115200 baud
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--paced") {
      paced = true;
    } else if (arg == "--port" && i + 1 < argc) {
      port = argv[++i];
    } else if (arg == "--count" && i + 1 < argc) {
      count = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: round_trip --port PORT [--count N] [--paced]\n");
      return 2;
    }
  }
  if (port.empty() || count < 1) {
    std::fprintf(stderr, "usage: round_trip --port PORT [--count N] [--paced]\n");
    return 2;
  }
  auto transport = hmc::open_port(port);
  if (!transport) {
    std::fprintf(stderr, "round_trip: %s\n", transport.error().message.c_str());
    return 3;
  }
  auto session = hmc::Session::open(std::move(*transport), {});
  if (!session) {
    std::fprintf(stderr, "round_trip: %s\n", session.error().message.c_str());
    return 3;
  }
  // A stop for an idle motor: the shortest command that is carried out and acknowledged.
  const hmc::Command stop = hmc::StepperMove{3, hmc::proto::kActionStop, 0, 0, 0};
  const size_t line_bytes = hmc::encode(stop).value().size() + 1;
  const size_t reply_bytes = hmc::encode_board_frame(hmc::BoardFrame{hmc::Ack{}}).value().size() + 1;
  std::vector<double> ms;
  ms.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    const auto start = std::chrono::steady_clock::now();
    auto reply = session.value()->execute(stop);
    const auto end = std::chrono::steady_clock::now();
    if (!reply) {
      std::fprintf(stderr, "round_trip: %s\n", reply.error().message.c_str());
      return 4;
    }
    ms.push_back(std::chrono::duration<double, std::milli>(end - start).count());
  }
  std::sort(ms.begin(), ms.end());
  const auto at = [&](double q) { return ms[static_cast<size_t>(q * static_cast<double>(ms.size() - 1))]; };
  const double wire = wire_ms(line_bytes + reply_bytes, 115200.0);
  const double line_wire = wire_ms(line_bytes, 115200.0);
  std::printf("%d round trips to %s: median %.3f ms (p10 %.3f, p90 %.3f, max %.3f)\n", count, port.c_str(), at(0.5),
              at(0.1), at(0.9), ms.back());
  std::printf("at 115200 baud the line (%zu bytes) takes %.3f ms on the wire, with its reply (%zu bytes) %.3f ms; "
              "median / wire time of both = %.3f\n",
              line_bytes, line_wire, reply_bytes, wire, at(0.5) / wire);
  std::printf("summary: | round trip of an acknowledged stop, %s | median %.3f ms | %.3f ms on the wire at 115200 | "
              "%.3f | host + board cost small beside the wire |\n",
              paced ? "board paced at 115200 baud" : "bytes delivered at once", at(0.5), wire, at(0.5) / wire);
  return 0;
}
