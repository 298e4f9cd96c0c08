// SERCOM USART and SPI master (sercom.h).
#include "sercom.h"

#include "../board/board.h"

namespace hmc::emu {
namespace {
constexpr uint8_t kDre = 1, kTxc = 2, kRxc = 4;
// Fields of CTRLA that are enable-protected (26.8.1/27.8.1): all but SWRST, ENABLE.
constexpr uint32_t kCtrlAProtected = ~0x3u;
// CTRLB is enable-protected except USART RXEN/TXEN and SPI RXEN (26.8.2, 27.8.2).
constexpr uint32_t kCtrlBProtected = ~((1u << 16) | (1u << 17));
// The receiver takes a byte whose baud is within ±4 % of its own (26.6.3.3, the receiver's
// baud tolerance for 16× oversampling with 8N1 is about ±4.5 %).
constexpr double kBaudTolerance = 0.04;
}  // namespace

Sercom::Sercom(Chip& chip, unsigned index) : chip_(chip), index_(index) {}

uint8_t Sercom::intflag() const {
  uint8_t f = txc_;
  if (enabled() && !tx_buffer_.has_value()) f |= kDre;
  if (!rx_fifo_.empty()) f |= kRxc;
  return f;
}

// USART, arithmetic 16× (26.6.2.3): f_baud = f_ref/16 · (1 − BAUD/65536); 10 bits per byte.
// SPI (27.6.2.3): f_sck = f_ref / (2 · (BAUD + 1)); 8 bits per byte.
uint64_t Sercom::byte_ps() const {
  const uint64_t ref = chip_.channel_hz(0x14 + index_);
  if (ref == 0) return UINT64_MAX;
  if (spi()) return 8 * Chip::kPsPerSecond * 2 * (uint64_t{baud_ & 0xFFu} + 1) / ref;
  const uint64_t denominator = ref * (65536 - uint64_t{baud_});
  if (denominator == 0) return UINT64_MAX;
  return 10 * Chip::kPsPerSecond * 16 * 65536 / denominator;
}

uint32_t Sercom::read(uint32_t offset, unsigned size) {
  if (touches(offset, size, 0x28, 2)) {
    uint16_t data = 0;
    if (!rx_fifo_.empty()) {
      data = rx_fifo_.front().first;
      rx_fifo_.pop_front();
      chip_.irq_changed();
    }
    return data;
  }
  RegisterBytes view(0x34);
  view.set(0x00, ctrla_, 4);
  view.set(0x04, ctrlb_, 4);
  view.set(0x0C, baud_, spi() ? 1 : 2);
  view.set(0x14, inten_, 1);
  view.set(0x16, inten_, 1);
  view.set(0x18, intflag(), 1);
  // STATUS shows the errors of the byte at the head of the FIFO, and sticky BUFOVF.
  view.set(0x1A, status_ | (rx_fifo_.empty() ? 0 : rx_fifo_.front().second), 2);
  // SYNCBUSY reads 0: each synchronised write's delay is charged as a stall instead.
  return view.get(offset, size);
}

void Sercom::write(uint32_t offset, uint32_t value, unsigned size) {
  if (touches(offset, size, 0x28, 2)) {
    write_data(static_cast<uint16_t>(value));
    return;
  }
  RegisterBytes view(0x34);
  view.set(0x00, ctrla_, 4);
  view.set(0x04, ctrlb_, 4);
  view.set(0x0C, baud_, 2);
  view.set(offset, value, size);
  const std::string name = "SERCOM" + std::to_string(index_);
  if (touches(offset, size, 0x00, 4)) {
    const uint32_t v = view.get(0, 4);
    if ((v & 1) != 0) {  // SWRST: all registers to reset, the block disabled (26.8.1)
      ctrla_ = ctrlb_ = 0;
      baud_ = 0;
      inten_ = txc_ = 0;
      status_ = 0;
      tx_buffer_.reset();
      shifting_ = false;
      last_bit_ = false;
      rx_fifo_.clear();
      chip_.charge_stall(5, chip_.channel_hz(0x14 + index_) ? chip_.channel_hz(0x14 + index_) : 1);
      chip_.irq_changed();
      return;
    }
    if (enabled() && ((v ^ ctrla_) & kCtrlAProtected) != 0) {
      chip_.violation("write to " + name + " CTRLA's enable-protected fields while enabled "
                      "(datasheet 26.8.1)");
      return;
    }
    if (((v ^ ctrla_) & 2) != 0) {
      const uint64_t hz = chip_.channel_hz(0x14 + index_);
      if (hz == 0) {
        chip_.violation(name + " enabled without its generic clock (GCLK channel " +
                        std::to_string(0x14 + index_) + " off; datasheet 26.6.2.2)");
        return;
      }
      chip_.charge_stall(5, hz);  // ENABLE synchronises: 26.6.6
    }
    ctrla_ = v;
  }
  if (touches(offset, size, 0x04, 4)) {
    const uint32_t v = view.get(4, 4);
    if (enabled() && ((v ^ ctrlb_) & kCtrlBProtected) != 0) {
      chip_.violation("write to " + name + " CTRLB's enable-protected fields while enabled "
                      "(datasheet 26.8.2)");
      return;
    }
    ctrlb_ = v;
  }
  if (touches(offset, size, 0x0C, 2)) {
    if (enabled()) {
      chip_.violation("write to " + name + " BAUD while enabled (datasheet 26.8.3: "
                      "enable-protected)");
      return;
    }
    baud_ = static_cast<uint16_t>(view.get(0x0C, 2));
  }
  RegisterBytes w(0x20);
  w.set(offset, value, size);
  if (touches(offset, size, 0x14, 1)) inten_ &= static_cast<uint8_t>(~w.get(0x14, 1));
  if (touches(offset, size, 0x16, 1)) inten_ |= static_cast<uint8_t>(w.get(0x16, 1));
  if (touches(offset, size, 0x18, 1)) txc_ &= static_cast<uint8_t>(~w.get(0x18, 1));  // TXC w1c
  if (touches(offset, size, 0x1A, 2)) status_ &= static_cast<uint16_t>(~w.get(0x1A, 2));
  if (touches(offset, size, 0x1A, 2) && !rx_fifo_.empty()) {
    rx_fifo_.front().second &= static_cast<uint16_t>(~w.get(0x1A, 2));
  }
  chip_.irq_changed();
  chip_.reschedule();
}

void Sercom::write_data(uint16_t byte) {
  // 26.6.2.4: DATA may be written only while DRE is set; a write when it is not is lost.
  if (!enabled() || tx_buffer_.has_value()) return;
  const bool transmitter = spi() || (ctrlb_ & (1u << 16)) != 0;
  if (!transmitter) return;
  tx_buffer_ = byte;
  txc_ = 0;
  if (!shifting_) start_shift();
  chip_.irq_changed();
  chip_.reschedule();
}

// CTRLA.DOPO (27.8.1): 0 DO on PAD0, 1 on PAD2, 2 on PAD3, 3 on PAD0.
unsigned Sercom::data_out_pad() const {
  constexpr unsigned kPad[4] = {0, 2, 3, 0};
  return kPad[(ctrla_ >> 16) & 3];
}

// MSB first unless CTRLA.DORD (bit 30) asks for LSB first (27.6.2.x "Data Register").
bool Sercom::pad_output(unsigned pad) const {
  if (!enabled() || !spi() || pad != data_out_pad()) return false;
  if (!shifting_ || shift_done_ps_ == UINT64_MAX) return last_bit_;
  const uint64_t now = chip_.now_ps();
  const uint64_t bit_ps = (shift_done_ps_ - shift_start_ps_) / 8;
  uint64_t bit = now <= shift_start_ps_ || bit_ps == 0 ? 0 : (now - shift_start_ps_) / bit_ps;
  if (bit > 7) bit = 7;
  const unsigned shift = (ctrla_ & (1u << 30)) != 0 ? static_cast<unsigned>(bit) : 7u - static_cast<unsigned>(bit);
  return ((shift_byte_ >> shift) & 1) != 0;
}

void Sercom::start_shift() {
  shift_byte_ = *tx_buffer_;
  tx_buffer_.reset();
  shifting_ = true;
  shift_start_ps_ = chip_.now_ps();
  const uint64_t span = byte_ps();
  shift_done_ps_ = span == UINT64_MAX ? UINT64_MAX : chip_.now_ps() + span;
}

void Sercom::receive(uint8_t byte, uint16_t status) {
  // Two-level FIFO plus the shift register (26.6.2.5): a byte completing while both levels
  // are full sets BUFOVF and is lost.
  if (rx_fifo_.size() >= 2) {
    status_ |= 1u << 2;
    ++rx_overflows_;
    return;
  }
  rx_fifo_.emplace_back(byte, status);
  chip_.irq_changed();
}

void Sercom::host_send(const std::string& bytes) {
  if (wire_.empty()) {
    const double wire_byte = 10.0 * Chip::kPsPerSecond / chip_.options().wire_baud;
    wire_next_ps_ = chip_.now_ps() + static_cast<uint64_t>(wire_byte);
  }
  for (const char c : bytes) wire_.push_back(static_cast<uint8_t>(c));
  chip_.reschedule();
}

std::string Sercom::take_output() {
  std::string out;
  out.swap(output_);
  return out;
}

uint64_t Sercom::next_event_ps() const {
  uint64_t next = shifting_ ? shift_done_ps_ : UINT64_MAX;
  if (!wire_.empty() && wire_next_ps_ < next) next = wire_next_ps_;
  return next;
}

void Sercom::advance(uint64_t now_ps) {
  while (!wire_.empty() && wire_next_ps_ <= now_ps) {
    const uint8_t byte = wire_.front();
    wire_.pop_front();
    const bool receiver = enabled() && usart() && (ctrlb_ & (1u << 17)) != 0;
    if (receiver) {
      const uint64_t ours = byte_ps();
      const double wire_byte = 10.0 * Chip::kPsPerSecond / chip_.options().wire_baud;
      const double error = ours == UINT64_MAX ? 1.0 : (static_cast<double>(ours) - wire_byte) / wire_byte;
      // Outside the tolerance the stop bit is sampled in the wrong place: a framing error.
      receive(byte, (error > kBaudTolerance || error < -kBaudTolerance) ? 2 : 0);
    }
    const double wire_byte = 10.0 * Chip::kPsPerSecond / chip_.options().wire_baud;
    wire_next_ps_ += static_cast<uint64_t>(wire_byte);
  }
  while (shifting_ && shift_done_ps_ <= now_ps) {
    // DRE is set: a DMA channel on this transmitter refills the buffer now, at the byte's end,
    // even inside a CPU bus stall (the buffer fills while the shift register is still busy).
    if (!tx_buffer_.has_value()) chip_.dma_trigger(index_);
    shifting_ = false;
    if (usart()) {
      output_.push_back(static_cast<char>(shift_byte_));
    } else {
      const bool lsb_first = (ctrla_ & (1u << 30)) != 0;
      const uint8_t in = chip_.board().spi_exchange(
          index_, static_cast<uint8_t>(shift_byte_),
          SpiBits{shift_start_ps_, (shift_done_ps_ - shift_start_ps_) / 8, data_out_pad(), lsb_first});
      last_bit_ = ((shift_byte_ >> (lsb_first ? 7 : 0)) & 1) != 0;
      if ((ctrlb_ & (1u << 17)) != 0) receive(in, 0);
    }
    if (tx_buffer_.has_value()) {
      const uint64_t done = shift_done_ps_;
      start_shift();
      if (shift_done_ps_ != UINT64_MAX) shift_done_ps_ = done + (shift_done_ps_ - now_ps);
      shift_start_ps_ = done;  // back to back: the next byte starts as this one ends
    } else {
      txc_ = kTxc;
    }
    chip_.irq_changed();
  }
}

}  // namespace hmc::emu
