// DMAC: the channels the image uses — the LED strips' SPI transmitters (SERCOM TX triggers, byte
// beats) and the STEP pulses (TC4 MC0/MC1 or TCC1/TCC2 MC0/MC1 triggers, word beats to PORT OUTSET/OUTCLR, each
// channel's descriptor linked to itself so it runs for ever). A channel, once enabled, fetches
// its descriptor from BASEADDR + 16·channel and moves one beat per trigger (CHCTRLB.TRIGACT
// BEAT) until BTCNT beats are done; then it fetches the descriptor DESCADDR points to, or, the
// last (DESCADDR 0), disables the channel and sets TCMPL. Triggers that arrive together are
// served in the channels' priority order. SAMD21 datasheet chapter 20 (DMAC), 20.6.2.
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
  // A timer's compare matches at `ps` (TRIGSRC values, `count` of them: a timer's compare
  // channels may match at one tick): the channels on them move one beat each, in priority order,
  // landing kTriggerToWriteCycles after the match.
  void timer_trigger(const unsigned* triggers, unsigned count, uint64_t ps);

 private:
  struct Channel {
    uint8_t ctrla = 0, inten = 0, intflag = 0;
    uint32_t ctrlb = 0;
    bool active = false;
    uint32_t source = 0, destination = 0, remaining = 0, next_descriptor = 0;
    unsigned beat = 1;  // bytes
    bool source_increments = false;
    bool block_interrupt = false;  // BTCTRL.BLOCKACT INT or BOTH
  };
  void start(unsigned channel);
  bool load(unsigned channel, uint32_t address);
  void serve(unsigned channel);
  void beat(unsigned channel, uint64_t ps);
  void block_done(unsigned channel);
  void watch_timers();
  Chip& chip_;
  uint16_t ctrl_ = 0;
  uint32_t base_ = 0, writeback_ = 0;
  uint8_t chid_ = 0;
  std::array<Channel, kChannels> channels_{};
};

}  // namespace hmc::emu
