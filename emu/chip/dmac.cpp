// DMAC (dmac.h). Registers (20.8): CTRL 0x00, BASEADDR 0x34, WRBADDR 0x38, CHID 0x3F,
// CHCTRLA 0x40, CHCTRLB 0x44, CHINTENCLR 0x4C, CHINTENSET 0x4D, CHINTFLAG 0x4E.
#include "dmac.h"

#include "sercom.h"

namespace hmc::emu {

bool Dmac::irq() const {
  for (const Channel& c : channels_) {
    if ((c.intflag & c.inten) != 0) return true;
  }
  return false;
}

uint32_t Dmac::read(uint32_t offset, unsigned size) {
  const Channel& c = channels_[chid_ % kChannels];
  RegisterBytes view(0x50);
  view.set(0x00, ctrl_, 2);
  view.set(0x34, base_, 4);
  view.set(0x38, writeback_, 4);
  view.set(0x3F, chid_, 1);
  view.set(0x40, c.ctrla, 1);
  view.set(0x44, c.ctrlb, 4);
  view.set(0x4C, c.inten, 1);
  view.set(0x4D, c.inten, 1);
  view.set(0x4E, c.intflag, 1);
  view.set(0x4F, c.active ? 3 : 0, 1);  // CHSTATUS: PEND, BUSY
  return view.get(offset, size);
}

void Dmac::write(uint32_t offset, uint32_t value, unsigned size) {
  RegisterBytes view(0x50);
  view.set(offset, value, size);
  if (touches(offset, size, 0x00, 2)) {
    const uint16_t v = static_cast<uint16_t>(view.get(0, 2));
    if ((v & 1) != 0) {  // SWRST (20.8.1)
      ctrl_ = 0;
      base_ = writeback_ = 0;
      channels_ = {};
    } else {
      ctrl_ = v;
    }
  }
  if (touches(offset, size, 0x34, 4)) {
    if ((ctrl_ & 2) != 0) {
      chip_.violation("write to DMAC BASEADDR while DMAENABLE is set (20.8.13: enable-protected)");
      return;
    }
    base_ = view.get(0x34, 4);
  }
  if (touches(offset, size, 0x38, 4)) writeback_ = view.get(0x38, 4);
  if (touches(offset, size, 0x3F, 1)) chid_ = static_cast<uint8_t>(view.get(0x3F, 1));
  Channel& c = channels_[chid_ % kChannels];
  if (touches(offset, size, 0x44, 4)) c.ctrlb = view.get(0x44, 4);
  if (touches(offset, size, 0x4C, 1)) c.inten &= static_cast<uint8_t>(~view.get(0x4C, 1));
  if (touches(offset, size, 0x4D, 1)) c.inten |= static_cast<uint8_t>(view.get(0x4D, 1));
  if (touches(offset, size, 0x4E, 1)) c.intflag &= static_cast<uint8_t>(~view.get(0x4E, 1));
  if (touches(offset, size, 0x40, 1)) {
    const uint8_t v = static_cast<uint8_t>(view.get(0x40, 1));
    c.ctrla = v & 2;
    if ((v & 2) == 0) c.active = false;
    else if (!c.active) start(chid_ % kChannels);
  }
  chip_.irq_changed();
  chip_.reschedule();
}

// 20.6.2.x: the descriptor (BTCTRL, BTCNT, SRCADDR, DSTADDR, DESCADDR) is read from BASEADDR
// + 16·channel. SRCADDR of an incrementing source is the end of the block.
void Dmac::start(unsigned channel) {
  Channel& c = channels_[channel];
  uint8_t d[16];
  if ((ctrl_ & 2) == 0) {
    chip_.violation("DMAC channel enabled while the DMAC is off (CTRL.DMAENABLE clear)");
    return;
  }
  if (!chip_.memory().read(base_ + 16 * channel, d, 16)) {
    chip_.violation("DMAC descriptor outside RAM");
    return;
  }
  const uint16_t btctrl = static_cast<uint16_t>(d[0] | d[1] << 8);
  const uint16_t btcnt = static_cast<uint16_t>(d[2] | d[3] << 8);
  const uint32_t src = uint32_t{d[4]} | uint32_t{d[5]} << 8 | uint32_t{d[6]} << 16 | uint32_t{d[7]} << 24;
  const uint32_t dst = uint32_t{d[8]} | uint32_t{d[9]} << 8 | uint32_t{d[10]} << 16 | uint32_t{d[11]} << 24;
  if ((btctrl & 1) == 0) {
    chip_.violation("DMAC channel " + std::to_string(channel) + " enabled with an invalid "
                    "descriptor (BTCTRL.VALID clear)");
    return;
  }
  if (((btctrl >> 8) & 3) != 0) {
    chip_.violation("DMAC beat sizes other than byte are not modelled");
    return;
  }
  c.source_increments = (btctrl & (1u << 10)) != 0;
  c.remaining = btcnt;
  c.source = c.source_increments ? src - btcnt : src;
  c.destination = dst;
  c.active = true;
}

void Dmac::advance(uint64_t) {
  for (unsigned i = 0; i < kChannels; ++i) {
    if (channels_[i].active) serve(i);
  }
}

void Dmac::sercom_ready(unsigned sercom) {
  for (unsigned i = 0; i < kChannels; ++i) {
    if (channels_[i].active && ((channels_[i].ctrlb >> 8) & 0x3F) == 2 * sercom + 2) serve(i);
  }
}

void Dmac::serve(unsigned i) {
  Channel& c = channels_[i];
  if (!c.active) return;
  const unsigned trigger = (c.ctrlb >> 8) & 0x3F;
  // SERCOMn TX trigger 2n+2 (20.8.17, TRIGSRC): one beat whenever DATA is empty.
  if (trigger < 2 || trigger > 13 || trigger % 2 != 0) {
    chip_.violation("DMAC trigger " + std::to_string(trigger) + " is not modelled");
    return;
  }
  Sercom& sercom = chip_.sercom((trigger - 2) / 2);
  while (c.remaining > 0 && sercom.data_empty()) {
    uint8_t byte = 0;
    if (!chip_.memory().read(c.source, &byte, 1)) {
      chip_.violation("DMAC read outside memory");
      return;
    }
    sercom.dma_write(byte);
    if (c.source_increments) ++c.source;
    --c.remaining;
  }
  if (c.remaining == 0) {
    c.active = false;
    c.ctrla = 0;
    c.intflag |= 2;  // TCMPL
    chip_.irq_changed();
  }
}

}  // namespace hmc::emu
