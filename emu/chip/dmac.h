// DMAC: the channels the image uses to feed the LED strips' SPI transmitters. A channel, once
// enabled, fetches its descriptor from BASEADDR and moves one beat per trigger (the SERCOM's
// DRE) until BTCNT beats are done; a last descriptor (DESCADDR 0, BLOCKACT 0) disables the
// channel and sets TCMPL. SAMD21 datasheet chapter 20 (DMAC), 20.6.2.
#pragma once

#include <array>
#include <cstdint>

#include "chip.h"

namespace hmc::emu {

class Dmac : public Peripheral, public Timed {
 public:
  static constexpr unsigned kChannels = 12;
  explicit Dmac(Chip& chip) : chip_(chip) {}
  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;
  void advance(uint64_t now_ps) override;
  uint64_t next_event_ps() const override { return UINT64_MAX; }
  bool irq() const;
  // SERCOM `sercom`'s transmitter wants a byte (its DRE trigger) at the end of a byte it shifted:
  // a channel on that trigger moves its beat then. The DMAC is a bus master of its own, so a
  // CPU bus stall (a synchronised write) does not hold it up; advance() alone would serve the
  // trigger only after the stall.
  void sercom_ready(unsigned sercom);

 private:
  struct Channel {
    uint8_t ctrla = 0, inten = 0, intflag = 0;
    uint32_t ctrlb = 0;
    bool active = false;
    uint32_t source = 0, destination = 0, remaining = 0;
    bool source_increments = false;
  };
  void start(unsigned channel);
  void serve(unsigned channel);
  Chip& chip_;
  uint16_t ctrl_ = 0;
  uint32_t base_ = 0, writeback_ = 0;
  uint8_t chid_ = 0;
  std::array<Channel, kChannels> channels_{};
};

}  // namespace hmc::emu
