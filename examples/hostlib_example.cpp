// Using libhmc directly: open a board (the simulated one unless a port is given), move a motor
// with a ramp and wait for it, turn a servo, light a strip, then read the board's status.
//
//   build/default/examples/hostlib_example                 # sim://example, fast
//   build/default/examples/hostlib_example /dev/ttyUSB0    # a real board
#include <cstdio>
#include <string>

#include "hmc/session.h"
#include "hmc/transport.h"

int main(int argc, char** argv) {
  const std::string port = argc > 1 ? argv[1] : "sim://example?fast&fresh&nosave";
  hmc::Result<std::unique_ptr<hmc::Transport>> link = hmc::open_port(port);
  if (!link) {
    std::fprintf(stderr, "%s\n", link.error().message.c_str());
    return 3;
  }
  auto opened = hmc::Session::open(std::move(link.value()), {});
  if (!opened) {
    std::fprintf(stderr, "%s\n", opened.error().message.c_str());
    return 3;
  }
  hmc::Session& board = *opened.value();
  std::printf("board: %s\n", board.description().c_str());

  // Every call checks the command against the board's rules first, then waits for the reply.
  const hmc::Command commands[] = {
      hmc::SetSetting{1, hmc::proto::kSettingAccel, 8000},                 // 8000 steps/s² on motor 1
      hmc::StepperMove{1, hmc::proto::kActionForward, 16, 3200, 250},      // one turn at 1/16 step
  };
  for (const hmc::Command& c : commands) {
    if (auto reply = board.execute(c); !reply) {
      std::fprintf(stderr, "refused: %s\n", reply.error().message.c_str());
      return 1;
    }
  }
  if (auto done = board.wait_until_idle({1}); !done) {
    std::fprintf(stderr, "%s\n", done.error().message.c_str());
    return 4;
  }
  (void)board.execute(hmc::ServoMove{1, 135});
  (void)board.execute(hmc::LedColor{1, 255, 128, 0, 0});

  if (auto fresh = board.refresh(); !fresh) return 4;
  for (const hmc::MotorStatus& m : board.model().motors) {
    std::printf("motor %u: %s at %s full steps\n", static_cast<unsigned>(m.motor), hmc::motor_state_name(m.state),
                hmc::steps_text(m.position).c_str());
  }
  return 0;
}
