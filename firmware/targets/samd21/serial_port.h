// SerialPort on the SAMD21: the command line on SERCOM5 (board.h: PB22 TX, PB23 RX, 115200 8N1,
// to the FT232RL). Both directions are interrupt driven through ring buffers:
//  - receive: the interrupt moves each byte into a 256-byte ring; read_byte() takes from it.
//    A byte arriving with the ring full is dropped and counted (rx_dropped()); so are bytes
//    the USART itself lost (BUFOVF) or received damaged (FERR). Either way one NUL takes their
//    place in the ring (the ring keeps a place free for it), so the line that lost them is
//    refused as bad_byte where they were.
//  - transmit: write() copies into a 256-byte ring and enables the data-register-empty
//    interrupt, which sends. write() waits only when the ring is full (a reply is far shorter).
// One producer and one consumer per ring, so no locking: the index each side writes is its own.
// The rings are zero-initialised statics of serial_port.cpp (in .bss, not copied from flash):
// there is one command UART, so one SerialPort.
#pragma once

#include <stdint.h>

#include "core/hal.h"

namespace hmc::samd21 {

class SerialPort final : public hal::SerialPort {
 public:
  void init();

  int read_byte() override;
  void write(const uint8_t* bytes, uint32_t count) override;

  // The SERCOM5 interrupt.
  void on_interrupt();

  static constexpr uint32_t kRingSize = 256;  // power of two: indices wrap by masking

  uint32_t rx_dropped() const { return rx_dropped_; }
  uint32_t rx_errors() const { return rx_errors_; }  // framing, parity or overrun

 private:
  volatile uint32_t rx_head_ = 0;  // written by the interrupt
  volatile uint32_t rx_tail_ = 0;  // written by read_byte()
  volatile uint32_t tx_head_ = 0;  // written by write()
  volatile uint32_t tx_tail_ = 0;  // written by the interrupt
  volatile uint32_t rx_dropped_ = 0;
  volatile uint32_t rx_errors_ = 0;
  bool rx_marked_ = false;  // the interrupt's only: the last byte stored marks a loss
};

}  // namespace hmc::samd21
