// The SAM-BA monitor's commands byte for byte, and the UF2 drive's block rules, on the bootloader's
// memory map (bare_chip.h).
#include "samba_monitor.h"

#include <catch2/catch.hpp>

#include "bare_chip.h"
#include "uf2.h"
#include "uf2_drive.h"

namespace hmc::emu {
namespace {

struct Fixture {
  BareChip chip;
  std::vector<std::string> log;
  SambaMonitor monitor{chip, [this](const std::string& line) { log.push_back(line); }};

  std::string send(const std::string& text) {
    return monitor.receive(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  }
};

std::string le(uint32_t v, unsigned size) {
  std::string out;
  for (unsigned i = 0; i < size; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
  return out;
}

TEST_CASE_METHOD(Fixture, "identification: binary mode, version with the extensions, CPUID and DSU DID") {
  CHECK(send("N#") == "\n\r");
  CHECK(send("V#") == "v2.0 [Arduino:XYZ] hmc-emu\n\r");
  CHECK(send("wE000ED00,4#") == le(0x410CC601, 4));
  CHECK(send("w41002018,4#") == le(0x10010305, 4));
  CHECK(send("w41004008,4#") == le(0x00031000, 4));  // NVMCTRL PARAM
  CHECK(log.empty());
}

TEST_CASE_METHOD(Fixture, "word, half-word and byte writes and reads of RAM; commands may arrive split") {
  CHECK(send("W20001000,").empty());
  CHECK(send("A1B2C3D4#").empty());
  CHECK(send("w20001000,4#") == le(0xA1B2C3D4, 4));
  send("H20001004,BEEF#O20001006,7#");
  CHECK(send("h20001004,2#") == le(0xBEEF, 2));
  CHECK(send("o20001006,1#") == std::string(1, '\x07'));
}

TEST_CASE_METHOD(Fixture, "S takes binary bytes, R answers them, Z their CRC-16") {
  std::string payload = "S20002000,5#";
  payload += std::string("\x00\x23\x00\xFFZ", 5);  // binary, including '#'-free bytes and a letter
  CHECK(send(payload).empty());
  CHECK(send("R20002000,5#") == std::string("\x00\x23\x00\xFFZ", 5));
  CHECK(send("S20002100,9#123456789").empty());
  CHECK(send("Z20002100,9#") == "Z000031C3#\n\r");  // CRC-16/XMODEM check value of "123456789"
}

TEST_CASE_METHOD(Fixture, "X erases from an address, Y writes the buffer through NVMCTRL") {
  chip.nvm().load_flash(0x2000, std::vector<uint8_t>(0x3E000, 0x00));
  CHECK(send("X00002000#") == "X\n\r");
  CHECK(chip.nvm().flash()[0x2000] == 0xFF);
  CHECK(chip.nvm().flash()[0x3FFFF] == 0xFF);
  std::string data;
  for (int i = 0; i < 128; ++i) data += static_cast<char>(i);
  send("S20004000,80#" + data);
  CHECK(send("Y20004000,0#") == "Y\n\r");
  CHECK(send("Y00002040,80#") == "Y\n\r");
  CHECK(chip.nvm().flash()[0x2040] == 0);
  CHECK(chip.nvm().flash()[0x20BF] == 127);
  CHECK(chip.nvm().flash()[0x20C0] == 0xFF);
  CHECK(log.empty());
}

TEST_CASE_METHOD(Fixture, "the boot section refuses X and Y: logged with LOCKE, nothing changed") {
  chip.nvm().load_flash(0, std::vector<uint8_t>(0x2000, 0x5A));
  CHECK(send("X00000000#") == "X\n\r");
  CHECK(chip.nvm().flash()[0] == 0x5A);
  REQUIRE(log.size() == 1);
  CHECK(log[0].find("LOCKE") != std::string::npos);
}

TEST_CASE_METHOD(Fixture, "AIRCR with VECTKEY and SYSRESETREQ asks for a reset; without the key nothing") {
  send("WE000ED0C,00000004#");
  CHECK_FALSE(chip.reset_requested());
  send("WE000ED0C,05FA0004#");
  CHECK(chip.reset_requested());
}

TEST_CASE_METHOD(Fixture, "bad requests are logged and answered so the host stays in step") {
  CHECK(send("w50000000,4#") == le(0, 4));
  CHECK(send("G00002000#").empty());
  CHECK(send("Q#").empty());
  REQUIRE(log.size() == 3);
  CHECK(log[0].find("read of 0x50000000") != std::string::npos);
  CHECK(log[1].find("needs the emulated CPU") != std::string::npos);
  CHECK(log[2].find("'Q'") != std::string::npos);
}

TEST_CASE("UF2 blocks: written at 0x2000 and above, other families and the boot section skipped") {
  BareChip chip;
  BootFlash flash(chip);
  std::vector<uint8_t> image(600);
  for (size_t i = 0; i < image.size(); ++i) image[i] = static_cast<uint8_t>(i * 7);
  std::vector<uint8_t> file = uf2::from_bin(image, uf2::Options{});
  uf2::Options low;
  low.base = 0x1000;
  const std::vector<uint8_t> boot = uf2::from_bin(image, low);
  file.insert(file.end(), boot.begin(), boot.begin() + 512);
  uf2::Options other;
  other.base = 0x8000;
  other.family = 0xADA52840;
  const std::vector<uint8_t> foreign = uf2::from_bin(image, other);
  file.insert(file.end(), foreign.begin(), foreign.begin() + 512);
  std::vector<std::string> log;
  std::string error;
  CHECK(Uf2Drive::flash_file(file, flash, error, [&](const std::string& l) { log.push_back(l); }) == 3);
  CHECK(error.empty());
  CHECK(std::equal(image.begin(), image.end(), chip.nvm().flash().begin() + 0x2000));
  CHECK(chip.nvm().flash()[0x1000] == 0xFF);
  CHECK(chip.nvm().flash()[0x8000] == 0xFF);
  REQUIRE(log.size() == 2);
  CHECK(log[0].find("outside the application flash") != std::string::npos);
  CHECK(log[1].find("family 0xADA52840") != std::string::npos);
}

}  // namespace
}  // namespace hmc::emu
