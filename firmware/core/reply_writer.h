// Reply frames: what the board sends back, in the same grammar as the commands it reads
// (docs/protocol.md, "Replies"), so one codec reads both directions.
//
//   STX#1#ACK#0#ETX                          the line was accepted and carried out
//   STX#4#NAK#<reason>#<token>#<offset>#<checksum>#ETX
//                                            the line was refused: reason code, the token it
//                                            concerns (255: none), byte offset in the line
//
// One reply per non-blank line received, in order, each ended by LF.
// Freestanding: formats into a stack buffer, no library calls.
#pragma once

#include <stdint.h>

#include "hal.h"
#include "protocol_facts.h"

namespace hmc::fw {

// Writes STX#<count+1>#<name>#<v1>…#<sum of values mod 256>#ETX and LF.
void write_frame(hal::SerialPort& port, const char* name, const uint32_t* values, uint32_t count);

void write_ack(hal::SerialPort& port);
void write_nak(hal::SerialPort& port, proto::Reason reason, uint8_t token, uint8_t offset);

}  // namespace hmc::fw
