// Injected events on the emulated board (events.h).
#include "events.h"

#include <cinttypes>
#include <cstdio>

#include "board/board.h"
#include "chip/chip.h"

namespace hmc::emu {

void apply_board_event(Chip& chip, const sim::SimCommand& command) {
  Board& board = chip.board();
  const unsigned motor = command.motor - 1u;  // the parser allows 1-2 (switches), 1-3 (fault)
  switch (command.action) {
    case sim::Action::kPress: board.hold_limit(motor, command.end, 1); break;
    case sim::Action::kRelease: board.hold_limit(motor, command.end, 0); break;
    case sim::Action::kAuto: board.hold_limit(motor, command.end, -1); break;
    case sim::Action::kEstop: board.set_switch("emergency", true); break;
    case sim::Action::kEstopRelease: board.set_switch("emergency", false); break;
    case sim::Action::kFault: board.latch_fault(motor, command.end); break;
    case sim::Action::kSend:
    case sim::Action::kStatus: break;  // not board events: apply_event(), emu_status_json()
  }
}

std::string emu_status_json(const Board& board, uint64_t now_ps) {
  std::string out;
  char text[160];
  // hmc-sim's tick is 1/48 µs: ps * 48 / 10^6.
  std::snprintf(text, sizeof text, "{\"t\":%" PRIu64 ",\"emergency\":%s,\"motors\":[", now_ps / 1000000u * 48u +
                now_ps % 1000000u * 48u / 1000000u, board.emergency() ? "true" : "false");
  out += text;
  for (unsigned m = 0; m < 3; ++m) {
    const Board::Axis& axis = board.axis(m);
    const uint16_t ctrl = board.driver(m).regs[0];
    // DRV8711 CTRL (7.6.1): bit 0 ENBL, bits 6:3 MODE = log2 of the microsteps per full step.
    const unsigned mode = (ctrl >> 3) & 0xF;
    std::string switches = "null";
    if (m < 2) {
      switches = std::string("[") + (axis.pressed[0] ? "true" : "false") + "," + (axis.pressed[1] ? "true" : "false") + "]";
    }
    std::snprintf(text, sizeof text,
                  "%s{\"motor\":%u,\"pos\":%" PRId64 ",\"steps\":%" PRIu64 ",\"switches\":%s,\"microstep\":%u,"
                  "\"enabled\":%s}",
                  m == 0 ? "" : ",", m + 1, axis.position, axis.steps, switches.c_str(), mode <= 8 ? 1u << mode : 0u,
                  (ctrl & 1u) != 0 ? "true" : "false");
    out += text;
  }
  return out + "]}";
}

}  // namespace hmc::emu
