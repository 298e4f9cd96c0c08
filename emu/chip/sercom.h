// SERCOM in the two modes the image uses: USART (the command line to the host) and SPI master
// (the DRV8711 bus, the LED strips). Both modes: a one-byte transmit buffer before the shift
// register, a two-level receive FIFO, the flags and interrupt of datasheet 26.8 (USART) and
// 27.8 (SPI). Bytes are paced by the BAUD register, and the host's bytes by the wire's baud.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "chip.h"

namespace hmc::emu {

class Sercom : public Peripheral, public Timed {
 public:
  Sercom(Chip& chip, unsigned index);
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override;
  bool irq() const { return (intflag() & inten_) != 0; }

  // USART: bytes from the host onto the RX wire; bytes the USART finished sending.
  void host_send(const std::string& bytes);
  std::string take_output();
  bool receiving() const { return !wire_.empty(); }
  bool transmitting() const { return shifting_ || tx_buffer_.has_value(); }
  uint64_t rx_overflows() const { return rx_overflows_; }
  // For the DMAC: the DRE trigger and a DATA write.
  bool data_empty() const { return enabled() && !tx_buffer_.has_value(); }
  void dma_write(uint8_t byte) { write_data(byte); }
  // SPI master: the level on PAD[pad] now (the data-out pad while a byte shifts out, its last bit
  // between bytes); false for any other pad or mode.
  bool pad_output(unsigned pad) const;

 private:
  bool enabled() const { return (ctrla_ & 2) != 0; }
  bool usart() const { return ((ctrla_ >> 2) & 7) == 1; }
  bool spi() const { return ((ctrla_ >> 2) & 7) == 3; }
  unsigned data_out_pad() const;
  uint8_t intflag() const;
  uint64_t byte_ps() const;
  void write_data(uint16_t byte);
  void start_shift();
  void receive(uint8_t byte, uint16_t status);

  Chip& chip_;
  unsigned index_;
  uint32_t ctrla_ = 0, ctrlb_ = 0;
  uint16_t baud_ = 0;
  uint8_t inten_ = 0;
  uint8_t txc_ = 0;
  uint16_t status_ = 0;
  std::optional<uint16_t> tx_buffer_;
  bool shifting_ = false;
  uint16_t shift_byte_ = 0;
  uint64_t shift_done_ps_ = 0;
  uint64_t shift_start_ps_ = 0;
  bool last_bit_ = false;  // SPI: the data-out level after the last byte
  std::deque<std::pair<uint16_t, uint16_t>> rx_fifo_;  // byte, STATUS bits it brings
  std::deque<uint8_t> wire_;                           // host bytes not yet on the wire
  uint64_t wire_next_ps_ = 0;                          // when the next host byte completes
  std::string output_;
  uint64_t rx_overflows_ = 0;
};

}  // namespace hmc::emu
