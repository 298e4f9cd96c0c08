// hmc-sim's injected events (docs/sim.md, "Injected events": press, release, auto, estop, estop
// release, fault, send, status) carried out on the emulated board, the one implementation behind
// hmc-emu's --script and its control channel.
#pragma once

#include <cstdint>
#include <string>

#include "sim_script.h"

namespace hmc::emu {

class Board;
class Chip;

// Carries out anything but `status` at once. `send` puts the line on the UART's wire through
// `send_line` (which holds it while the board cannot take it yet).
template <typename SendLine>
void apply_event(Chip& chip, const sim::SimCommand& command, SendLine&& send_line);

// One switch, fault or emergency change (everything but send and status).
void apply_board_event(Chip& chip, const sim::SimCommand& command);

// The control channel's `status` answer: one JSON object (no line feed) with the fields of
// hmc-sim's that the emulated board knows: t (virtual time in hmc-sim's ticks, 1/48 µs),
// emergency, and per motor pos (1/256 step), steps (STEP edges), switches, microstep and
// enabled (the DRV8711's CTRL as the firmware last wrote it). The firmware's own state (fw_pos,
// state, homed) lives in the image's RAM: ask the board (STA).
std::string emu_status_json(const Board& board, uint64_t now_ps);

template <typename SendLine>
void apply_event(Chip& chip, const sim::SimCommand& command, SendLine&& send_line) {
  if (command.action == sim::Action::kSend) {
    send_line(command.text + "\n");
  } else if (command.action != sim::Action::kStatus) {
    apply_board_event(chip, command);
  }
}

}  // namespace hmc::emu
