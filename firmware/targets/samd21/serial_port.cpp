// SerialPort (serial_port.h). USART setup: SAMD21 datasheet "SERCOM USART" (internal clock,
// asynchronous, 16× oversampling with arithmetic baud, LSB first, 8 data bits, no parity, one
// stop bit); pads and baud value: HARDWARE.md.
#include "serial_port.h"

#include "board.h"
#include "clocks.h"
#include "irq.h"
#include "pins.h"
#include "reg_access.h"
#include "regs_sercom.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kBase = sercom::base(board::uart::kSercom);
constexpr uint32_t kSize = SerialPort::kRingSize;
constexpr uint32_t kMask = kSize - 1;

// Stands in the received stream where bytes were lost or damaged: NUL is a bad byte anywhere
// in a line (docs/protocol.md, "Link"), so the line that lost them is refused, never
// parsed spliced from what is left.
constexpr uint8_t kLostMarker = 0;

uint8_t rx_ring[kSize];
uint8_t tx_ring[kSize];

}  // namespace

void SerialPort::init() {
  set32(pm::kApbCMask, pm::kApbCSercom0 << board::uart::kSercom);
  clock_connect(gclk::kIdSercom0 + board::uart::kSercom, kGclkCpu);

  r32(kBase + sercom::kCtrlA) = sercom::kSwRst;
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncSwRst);
  r32(kBase + sercom::kCtrlA) = sercom::kModeUsartInternalClock | sercom::kSamprArithmetic16x |
                                sercom::txpo(board::uart::kTxpo) |
                                sercom::rxpo(board::uart::kRxPad) | sercom::kDordLsbFirst;
  r16(kBase + sercom::kBaud) = sercom::usart_baud(board::kCpuHz, board::uart::kBaud);
  r32(kBase + sercom::kCtrlB) = sercom::kTxEn | sercom::kRxEn;  // 8 bits, 1 stop bit
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncCtrlB);

  pin_input(board::uart::kRx, true);  // idle high if the FT232RL is unpowered
  pin_function(board::uart::kRx, board::uart::kRxFunction);
  pin_function(board::uart::kTx, board::uart::kTxFunction);

  r8(kBase + sercom::kIntEnSet) = static_cast<uint8_t>(sercom::kIntRxc);
  const uint32_t irq = irqn::kSercom0 + board::uart::kSercom;
  nvic_set_priority(irq, board::kPrioritySerial);
  nvic_enable(irq);
  set32(kBase + sercom::kCtrlA, sercom::kEnable);
  wait_clear32(kBase + sercom::kSyncBusy, sercom::kSyncEnable);
}

int SerialPort::read_byte() {
  const uint32_t tail = rx_tail_;
  if (tail == rx_head_) return -1;
  const uint8_t byte = rx_ring[tail & kMask];
  rx_tail_ = tail + 1;
  return byte;
}

void SerialPort::write(const uint8_t* bytes, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t head = tx_head_;
    while (head - tx_tail_ >= kSize) {
      // Ring full: the interrupt is draining it (one byte per 87 µs).
    }
    tx_ring[head & kMask] = bytes[i];
    tx_head_ = head + 1;
    r8(kBase + sercom::kIntEnSet) = static_cast<uint8_t>(sercom::kIntDre);
  }
}

void SerialPort::on_interrupt() {
  const uint32_t flags = r8(kBase + sercom::kIntFlag);
  if ((flags & sercom::kIntRxc) != 0) {
    const uint32_t status = r16(kBase + sercom::kStatus) & sercom::kStatusErrors;
    if (status != 0) {
      r16(kBase + sercom::kStatus) = static_cast<uint16_t>(status);  // write 1 to clear
      rx_errors_ = rx_errors_ + 1u;
    }
    const uint8_t byte = static_cast<uint8_t>(r16(kBase + sercom::kData));  // clears RXC
    // BUFOVF: bytes before this one were lost in the USART; FERR/PERR: this one is damaged;
    // a full ring: this one is dropped. Data takes a place only while another stays free, so
    // the marker of a loss always fits, right where the loss is.
    uint32_t head = rx_head_;
    uint32_t free = kSize - (head - rx_tail_);
    const auto mark_loss = [&] {
      if (rx_marked_) return;  // the marker stored last already stands for this loss
      rx_ring[head++ & kMask] = kLostMarker;
      --free;
      rx_marked_ = true;
    };
    if ((status & sercom::kStatusBufOvf) != 0) mark_loss();
    if ((status & ~sercom::kStatusBufOvf) != 0) {
      mark_loss();
    } else if (free >= 2) {
      rx_ring[head++ & kMask] = byte;
      rx_marked_ = false;
    } else {
      rx_dropped_ = rx_dropped_ + 1u;
      mark_loss();
    }
    rx_head_ = head;
  }
  if ((flags & sercom::kIntDre) != 0 && (r8(kBase + sercom::kIntEnSet) & sercom::kIntDre) != 0) {
    const uint32_t tail = tx_tail_;
    if (tail != tx_head_) {
      r16(kBase + sercom::kData) = tx_ring[tail & kMask];  // clears DRE
      tx_tail_ = tail + 1;
    } else {
      r8(kBase + sercom::kIntEnClr) = static_cast<uint8_t>(sercom::kIntDre);
    }
  }
}

}  // namespace hmc::samd21
