// Board → host frames: replies and events (docs/protocol.md "Replies", "Protocol v2"), in the
// same grammar as the commands the board reads, so one codec reads both directions.
//
//   STX#1#ACK#0#ETX                          the line was accepted and carried out
//   STX#4#NAK#<reason>#<token>#<offset>#<checksum>#ETX
//                                            refused: reason code, the token it concerns (255:
//                                            none), byte offset in the line
//   VER, STA, STB, STL, SET                  answers to queries; EV*: events
//
// Each frame ends with LF. In CRC-16 mode the checksum field is the CRC of the frame's bytes up
// to it (crc16.h). Freestanding: formats into a stack buffer, no library calls.
#pragma once

#include <stdint.h>

#include "crc16.h"
#include "hal.h"
#include "protocol_facts.h"

namespace hmc::fw {

// Writes the frame `id` with its table's number of values (proto::kBoardFrames).
void write_frame(hal::SerialPort& port, proto::BoardFrameId id, const uint32_t* values,
                 proto::ChecksumMode mode);

void write_ack(hal::SerialPort& port, proto::ChecksumMode mode);
void write_nak(hal::SerialPort& port, proto::Reason reason, uint8_t token, uint8_t offset,
               proto::ChecksumMode mode);

// A signed position as the protocol's sign and magnitude pair; the magnitude saturates at
// proto::kIntMax, the largest number the grammar carries (only INT32_MIN is affected).
inline void put_signed(uint32_t* out, int32_t value) {
  const uint32_t magnitude = value < 0 ? 0u - static_cast<uint32_t>(value) : static_cast<uint32_t>(value);
  out[0] = value < 0 ? 1u : 0u;
  out[1] = magnitude > proto::kIntMax ? proto::kIntMax : magnitude;
}

}  // namespace hmc::fw
