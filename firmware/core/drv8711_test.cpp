// Tests of the DRV8711 register encoding and driver against a fake SPI bus that records every
// word and emulates the chip's register file. Expected words are written out by hand from the
// register map of the TI DRV8711 datasheet (SLVSC40H); currents are checked against the Pololu
// 36v4 formula full-scale = 2.75 V × TORQUE / (256 × ISGAIN × 0.030 Ω).
#include "drv8711.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

namespace {

using namespace hmc::fw::drv8711;

// A DRV8711 on a bus: writes store 12 bits, reads return them in the same transfer, RSTEP
// reads back 0 and a STATUS write clears the bits written as 0.
class FakeSpiBus : public hmc::hal::SpiBus {
 public:
  uint16_t transfer16(uint8_t chip, uint16_t word) override {
    chips.push_back(chip);
    words.push_back(word);
    const unsigned address = (word >> 12) & 7u;
    if ((word & 0x8000u) != 0) {
      if (chip_absent) return 0;
      return static_cast<uint16_t>(kJunkHighBits | registers[address]);
    }
    const uint16_t data = static_cast<uint16_t>(word & 0x0FFFu);
    if (address == 7) {
      registers[7] = static_cast<uint16_t>(registers[7] & data);
    } else if (address == 0) {
      registers[0] = static_cast<uint16_t>(data & ~0x004u);
    } else {
      registers[address] = data;
    }
    currents_ma.push_back(full_scale_ma());
    return 0;
  }

  // The full-scale current the register file sets now, by the board's formula.
  double full_scale_ma() const {
    const double gain = 5.0 * (1u << ((registers[0] >> 8) & 3u));
    return 1000.0 * 2.75 * (registers[1] & 0xFFu) / (256.0 * gain * 0.030);
  }

  // Words with the read bit set.
  size_t read_count() const {
    size_t count = 0;
    for (uint16_t word : words) {
      if ((word & 0x8000u) != 0) ++count;
    }
    return count;
  }

  static constexpr uint16_t kJunkHighBits = 0xA000;  // the driver must mask these off
  std::vector<uint8_t> chips;
  std::vector<uint16_t> words;
  std::vector<double> currents_ma;  // after each write
  uint16_t registers[8] = {0xC10, 0x1FF, 0x030, 0x080, 0x110, 0x040, 0xA59, 0x000};
  bool chip_absent = false;  // reads return 0, as from an unpowered chip
};

// The full-scale current of a setting, by the board's formula.
double full_scale_ma(CurrentSetting setting) {
  return 1000.0 * 2.75 * setting.torque / (256.0 * gain_of(setting.gain_code) * 0.030);
}

// HARDWARE.md's algorithm written plainly, with the divisions a host can afford.
CurrentSetting reference_setting(uint32_t milliamps) {
  uint32_t torque_bits = 768u * milliamps / 6875u;
  uint8_t gain_code = 3;
  while (torque_bits > 255) {
    torque_bits >>= 1;
    --gain_code;
  }
  return {gain_code, static_cast<uint8_t>(torque_bits)};
}

}  // namespace

TEST_CASE("SPI words carry read bit, address and 12 data bits") {
  CHECK(write_word(Register::kCtrl, 0xC10) == 0x0C10);
  CHECK(write_word(Register::kTorque, 0x1FF) == 0x11FF);
  CHECK(write_word(Register::kDrive, 0xA59) == 0x6A59);
  CHECK(write_word(Register::kStatus, 0) == 0x7000);
  CHECK(write_word(Register::kCtrl, 0xFC10) == 0x0C10);  // data beyond 12 bits dropped
  CHECK(read_word(Register::kCtrl) == 0x8000);
  CHECK(read_word(Register::kDecay) == 0xC000);
  CHECK(read_word(Register::kStatus) == 0xF000);
}

TEST_CASE("fields read and replace only their own bits") {
  CHECK(ctrl::kMode.mask() == 0x078);
  CHECK(ctrl::kGain.mask() == 0x300);
  CHECK(ctrl::kMode.get(0xC10) == 2);
  CHECK(ctrl::kMode.put(0xFFF, 0) == 0xF87);
  CHECK(ctrl::kMode.put(0x000, 0x1F) == 0x078);  // value wider than the field is cut
  CHECK(decay::kDecayMode.put(0x110, 5) == 0x510);
}

TEST_CASE("reset values decode to the datasheet's settings") {
  const Ctrl c = decode_ctrl(kResetValues[0]);
  CHECK_FALSE(c.enable);
  CHECK_FALSE(c.reverse);
  CHECK(c.mode == 2);  // 1/4 step
  CHECK(gain_of(c.gain_code) == 5);
  CHECK(c.dead_time_code == 3);  // 850 ns
  CHECK(decode_torque(kResetValues[1]).torque == 255);
  CHECK(decode_torque(kResetValues[1]).sample_threshold_code == 1);
  CHECK(decode_off(kResetValues[2]).off_time == 0x30);
  CHECK(decode_blank(kResetValues[3]).blank_time == 0x80);
  CHECK(decode_decay(kResetValues[4]).mode == DecayMode::kSlowMixed);
  CHECK(decode_decay(kResetValues[4]).decay_time == 0x10);
  CHECK(decode_stall(kResetValues[5]).threshold == 0x40);
  const Drive d = decode_drive(kResetValues[6]);
  CHECK(d.ocp_threshold_code == 1);
  CHECK(d.ocp_deglitch_code == 2);
  CHECK(d.low_side_time_code == 1);
  CHECK(d.high_side_time_code == 1);
  CHECK(d.low_side_current_code == 2);
  CHECK(d.high_side_current_code == 2);
}

TEST_CASE("encode places every field") {
  CHECK(encode(Ctrl{true, true, false, 8, false, 3, 1}) == 0x743);
  CHECK(encode(Ctrl{false, false, true, 0, true, 0, 0}) == 0x084);
  CHECK(encode(Torque{167, 1}) == 0x1A7);
  CHECK(encode(Off{0x30, true}) == 0x130);
  CHECK(encode(Blank{0x80, true}) == 0x180);
  CHECK(encode(Decay{0x10, DecayMode::kAutoMixed}) == 0x510);
  CHECK(encode(Stall{0x40, 3, 2}) == 0xB40);
  CHECK(encode(Drive{1, 2, 1, 1, 2, 2}) == 0xA59);
  CHECK(encode(Faults{true, false, false, false, false, true, false, true}) == 0xA1);
}

TEST_CASE("decode then encode gives back every defined bit of every value") {
  for (uint16_t v = 0; v <= 0xFFF; ++v) {
    INFO("value " << v);
    REQUIRE(encode(decode_ctrl(v)) == v);
    REQUIRE(encode(decode_torque(v)) == (v & 0x7FF));
    REQUIRE(encode(decode_off(v)) == (v & 0x1FF));
    REQUIRE(encode(decode_blank(v)) == (v & 0x1FF));
    REQUIRE(encode(decode_decay(v)) == (v & 0x7FF));
    REQUIRE(encode(decode_stall(v)) == v);
    REQUIRE(encode(decode_drive(v)) == v);
    REQUIRE(encode(decode_status(v)) == (v & 0x0FF));
  }
}

TEST_CASE("reset_settings writes the defaults, CTRL last, to its own chip") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 2);
  CHECK(bus.words.empty());  // construction sends nothing
  driver.reset_settings();
  const std::vector<uint16_t> expected = {0x11FF, 0x2030, 0x3080, 0x4110, 0x5040, 0x6A59, 0x0C10};
  CHECK(bus.words == expected);
  CHECK(bus.chips == std::vector<uint8_t>(7, 2));
  CHECK_FALSE(driver.enabled());
}

TEST_CASE("step modes 1..256 map to MODE 0..8; other counts are refused") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  const uint32_t microsteps[] = {1, 2, 4, 8, 16, 32, 64, 128, 256};
  const uint16_t words[] = {0x0C00, 0x0C08, 0x0C10, 0x0C18, 0x0C20,
                            0x0C28, 0x0C30, 0x0C38, 0x0C40};
  for (size_t i = 0; i < 9; ++i) {
    INFO(microsteps[i] << " microsteps");
    CHECK(step_mode_for(microsteps[i]) == static_cast<uint8_t>(i));
    bus.words.clear();
    CHECK(driver.set_step_mode(microsteps[i]) == Status::kOk);
    CHECK(bus.words == std::vector<uint16_t>{words[i]});
  }
  bus.words.clear();
  for (uint32_t bad : {0u, 3u, 5u, 6u, 12u, 100u, 255u, 257u, 512u, 1024u, 0x80000000u,
                       0xFFFFFFFFu}) {
    INFO(bad << " microsteps");
    CHECK(step_mode_for(bad) == kNoStepMode);
    CHECK(driver.set_step_mode(bad) == Status::kUnsupportedMicrostep);
  }
  CHECK(bus.words.empty());
  CHECK(decode_ctrl(driver.shadow(Register::kCtrl)).mode == 8);  // unchanged by refusals
}

TEST_CASE("worked current values come out exactly") {
  struct Case {
    uint32_t milliamps;
    uint8_t gain;
    uint8_t torque;
  };
  const Case cases[] = {
      {1000, 40, 111}, {2000, 40, 223}, {3000, 20, 167}, {4000, 20, 223},  // HARDWARE.md
      {500, 40, 55},   {3500, 20, 195}, {0, 40, 0},      {2280, 40, 254},  {2300, 20, 128},
  };
  for (const Case& c : cases) {
    INFO(c.milliamps << " mA");
    const CurrentSetting setting = current_setting_for(c.milliamps);
    CHECK(gain_of(setting.gain_code) == c.gain);
    CHECK(setting.torque == c.torque);
  }
}

TEST_CASE("every current up to the cap matches the algorithm and the board's formula") {
  for (uint32_t milliamps = 0; milliamps <= kMaxCurrentMa; ++milliamps) {
    INFO(milliamps << " mA");
    const CurrentSetting setting = current_setting_for(milliamps);
    const CurrentSetting reference = reference_setting(milliamps);
    REQUIRE(setting.gain_code == reference.gain_code);
    REQUIRE(setting.torque == reference.torque);
    // Never above the request, and within one TORQUE step (one step at this gain) of it.
    const double one_step_ma = full_scale_ma({setting.gain_code, 1});
    REQUIRE(full_scale_ma(setting) <= milliamps + 1e-9);
    REQUIRE(milliamps - full_scale_ma(setting) < one_step_ma);
    // The highest gain that fits: below gain 40, TORQUE uses its top bit.
    REQUIRE((setting.gain_code == 3 || setting.torque >= 128));
  }
}

TEST_CASE("set_current_ma writes ISGAIN and TORQUE, keeping other bits, and caps") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 3);
  driver.reset_settings();
  bus.words.clear();
  // Gain 5 -> 20 rises: CTRL first. Then 20 -> 40 rises: CTRL first. Then 40 -> 20: TORQUE first.
  CHECK(driver.set_current_ma(3000) == Status::kOk);
  CHECK(driver.set_current_ma(1000) == Status::kOk);
  CHECK(driver.set_current_ma(4000) == Status::kOk);
  const std::vector<uint16_t> expected = {0x0E10, 0x11A7, 0x0F10, 0x116F, 0x11DF, 0x0E10};
  CHECK(bus.words == expected);
  CHECK(bus.registers[1] == 0x1DF);  // SMPLTH kept

  CHECK(driver.set_current_ma(4001) == Status::kCurrentCapped);
  CHECK(driver.set_current_ma(100000) == Status::kCurrentCapped);
  CHECK(driver.shadow(Register::kTorque) == 0x1DF);
  CHECK(decode_ctrl(driver.shadow(Register::kCtrl)).gain_code == 2);
}

TEST_CASE("a current change never passes through a higher current than both ends") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  const uint32_t requests[] = {2280, 2300, 2280, 1000, 4000, 500, 3500, 250, 1150, 1140, 4000};
  driver.set_current_ma(requests[0]);
  for (size_t i = 1; i < sizeof requests / sizeof requests[0]; ++i) {
    const double before = bus.full_scale_ma();
    bus.currents_ma.clear();
    driver.set_current_ma(requests[i]);
    const double after = bus.full_scale_ma();
    INFO(requests[i - 1] << " mA -> " << requests[i] << " mA");
    REQUIRE(bus.currents_ma.size() == 2);
    CHECK(bus.currents_ma[0] <= (before > after ? before : after));
  }
}

TEST_CASE("decay modes write DECMOD and keep TDECAY; reserved values are refused") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  const DecayMode modes[] = {DecayMode::kSlow,  DecayMode::kSlowMixed,     DecayMode::kFast,
                             DecayMode::kMixed, DecayMode::kSlowAutoMixed, DecayMode::kAutoMixed};
  const uint16_t words[] = {0x4010, 0x4110, 0x4210, 0x4310, 0x4410, 0x4510};
  for (size_t i = 0; i < 6; ++i) {
    bus.words.clear();
    CHECK(driver.set_decay_mode(modes[i]) == Status::kOk);
    CHECK(bus.words == std::vector<uint16_t>{words[i]});
  }
  bus.words.clear();
  CHECK(driver.set_decay_mode(static_cast<DecayMode>(6)) == Status::kReservedDecayMode);
  CHECK(driver.set_decay_mode(static_cast<DecayMode>(7)) == Status::kReservedDecayMode);
  CHECK(bus.words.empty());
}

TEST_CASE("enable, disable and direction change one CTRL bit from the shadow") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  driver.reset_settings();
  driver.set_step_mode(16);
  driver.set_current_ma(3000);
  const uint16_t configured = driver.shadow(Register::kCtrl);
  CHECK(configured == 0xE20);
  bus.registers[0] = 0xFFF;  // the chip's CTRL must not feed the change
  bus.words.clear();

  driver.enable();
  CHECK(driver.enabled());
  driver.set_direction(true);
  driver.set_direction(false);
  driver.disable();
  CHECK_FALSE(driver.enabled());
  const std::vector<uint16_t> expected = {0x0E21, 0x0E23, 0x0E21, 0x0E20};
  CHECK(bus.words == expected);
  CHECK(bus.read_count() == 0);
}

TEST_CASE("status bits decode one flag each; stall is not a fault") {
  const Faults none = decode_status(0x000);
  CHECK_FALSE(none.has_fault());
  CHECK_FALSE(none.has_stall());
  bool Faults::*const flags[] = {&Faults::overtemperature,   &Faults::overcurrent_a,
                                 &Faults::overcurrent_b,     &Faults::predriver_fault_a,
                                 &Faults::predriver_fault_b, &Faults::undervoltage,
                                 &Faults::stall,             &Faults::stall_latched};
  for (unsigned bit = 0; bit < 8; ++bit) {
    INFO("bit " << bit);
    const Faults faults = decode_status(static_cast<uint16_t>(1u << bit));
    for (unsigned other = 0; other < 8; ++other) CHECK(faults.*flags[other] == (other == bit));
    CHECK(faults.has_fault() == (bit < 6));
    CHECK(faults.has_stall() == (bit >= 6));
  }
  CHECK_FALSE(decode_status(0xF00).has_fault());  // reserved bits are not faults
}

TEST_CASE("read_status reads STATUS; clear_status writes 0 to it") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  bus.registers[7] = 0x0A2;  // AOCP, UVLO, STDLAT
  const Faults faults = driver.read_status();
  CHECK(bus.words == std::vector<uint16_t>{0xF000});
  CHECK(faults.overcurrent_a);
  CHECK(faults.undervoltage);
  CHECK(faults.stall_latched);
  CHECK_FALSE(faults.overcurrent_b);
  CHECK(faults.has_fault());

  driver.clear_status();
  CHECK(bus.words.back() == 0x7000);
  CHECK_FALSE(driver.read_status().has_fault());
  CHECK(driver.read_register(Register::kStatus) == 0);  // junk high bits masked
}

TEST_CASE("verify_settings reads CTRL..DRIVE and names the first mismatch") {
  FakeSpiBus bus;
  Drv8711 driver(bus, 1);
  driver.reset_settings();
  driver.set_current_ma(2000);
  driver.set_decay_mode(DecayMode::kAutoMixed);
  bus.words.clear();

  Verification result = driver.verify_settings();
  CHECK(result.status == Status::kOk);
  const std::vector<uint16_t> reads = {0x8000, 0x9000, 0xA000, 0xB000, 0xC000, 0xD000, 0xE000};
  CHECK(bus.words == reads);

  bus.registers[4] = 0x110;  // DECAY lost its mode
  bus.registers[5] = 0x000;
  result = driver.verify_settings();
  CHECK(result.status == Status::kMismatch);
  CHECK(result.reg == Register::kDecay);
  CHECK(result.expected == 0x510);
  CHECK(result.actual == 0x110);

  driver.apply_settings();  // rewriting the shadows repairs the chip
  CHECK(driver.verify_settings().status == Status::kOk);

  bus.chip_absent = true;
  result = driver.verify_settings();
  CHECK(result.status == Status::kMismatch);
  CHECK(result.reg == Register::kCtrl);
  CHECK(result.actual == 0);
}
