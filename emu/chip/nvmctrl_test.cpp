// NVMCTRL's rules, driven the way firmware and bossac drive them: registers written with the
// CMDEX key, the page buffer filled through the flash address space.
#include "nvmctrl.h"

#include <catch2/catch.hpp>

namespace hmc::emu {
namespace {

struct Fixture {
  std::vector<std::string> violations;
  Nvmctrl nvm{[this](const std::string& v) { violations.push_back(v); }};

  void command(uint8_t cmd) { nvm.write(Nvmctrl::kCtrlA, 0xA500u | cmd, 2); }
  void command_at(uint8_t cmd, uint32_t byte_address) {
    nvm.write(Nvmctrl::kAddr, byte_address / 2, 4);
    command(cmd);
  }
  void fill_page(uint32_t address, uint32_t first_word) {
    for (uint32_t i = 0; i < Nvmctrl::kPageSize; i += 4) nvm.write_memory(address + i, first_word + i, 4);
  }
  uint16_t status() { return static_cast<uint16_t>(nvm.read(Nvmctrl::kStatus, 2)); }
  uint8_t intflag() { return static_cast<uint8_t>(nvm.read(Nvmctrl::kIntFlag, 1)); }
};

TEST_CASE_METHOD(Fixture, "reset values and PARAM describe a 256 KB flash of 64-byte pages") {
  CHECK(nvm.read(Nvmctrl::kParam, 4) == 0x00031000);  // NVMP 4096, PSZ 3 = 64 bytes
  CHECK(nvm.read(Nvmctrl::kCtrlB, 4) == 0);          // MANW 0 at reset (errata)
  CHECK(intflag() == Nvmctrl::kReady);
  CHECK(nvm.read(Nvmctrl::kLock, 2) == 0xFFFF);
  CHECK(nvm.read_memory(0x100, 4) == 0xFFFFFFFF);
  CHECK(nvm.boot_section_size() == 8192);
}

TEST_CASE_METHOD(Fixture, "manual page write: PBC, fill the buffer, WP at ADDR") {
  nvm.write(Nvmctrl::kCtrlB, Nvmctrl::kManw | (1u << 1), 4);
  CHECK(nvm.read_wait_states() == 1);
  command(Nvmctrl::kPageBufferClear);
  fill_page(0x2040, 0x11223340);
  CHECK((status() & Nvmctrl::kLoad) != 0);
  CHECK(nvm.read_memory(0x2040, 4) == 0xFFFFFFFF);  // nothing written before WP
  CHECK(nvm.read(Nvmctrl::kAddr, 4) == (0x2040 + 60) / 2);  // page buffer writes update ADDR
  command_at(Nvmctrl::kWritePage, 0x2040);
  CHECK(nvm.read_memory(0x2040, 4) == 0x11223340);
  CHECK(nvm.read_memory(0x207C, 4) == 0x1122337C);
  CHECK(nvm.read_memory(0x2080, 4) == 0xFFFFFFFF);
  CHECK((status() & Nvmctrl::kLoad) == 0);
  CHECK(intflag() == Nvmctrl::kReady);
  CHECK(violations.empty());
}

TEST_CASE_METHOD(Fixture, "automatic page write when MANW is 0: the last word of the page writes it") {
  fill_page(0x3000, 0xA0B0C000);
  CHECK(nvm.read_memory(0x3000, 4) == 0xA0B0C000);
  CHECK(nvm.read_memory(0x303C, 4) == 0xA0B0C03C);
}

TEST_CASE_METHOD(Fixture, "writing without erasing only clears bits; ER erases the whole row") {
  nvm.write(Nvmctrl::kCtrlB, Nvmctrl::kManw, 4);
  nvm.write_memory(0x4000, 0x0F0F0F0F, 4);
  command_at(Nvmctrl::kWritePage, 0x4000);
  nvm.write_memory(0x4000, 0xFF00FF00, 4);
  command_at(Nvmctrl::kWritePage, 0x4000);
  CHECK(nvm.read_memory(0x4000, 4) == 0x0F000F00);
  nvm.write_memory(0x40C0, 0x12345678, 4);  // the row's last page
  command_at(Nvmctrl::kWritePage, 0x40C0);
  command_at(Nvmctrl::kErase, 0x4080);  // any address in the row erases the row
  CHECK(nvm.read_memory(0x4000, 4) == 0xFFFFFFFF);
  CHECK(nvm.read_memory(0x40C0, 4) == 0xFFFFFFFF);
}

TEST_CASE_METHOD(Fixture, "a wrong key or an unknown command sets PROGE and ERROR; both clear by writing one") {
  nvm.write(Nvmctrl::kCtrlA, 0xA400u | Nvmctrl::kErase, 2);
  CHECK((status() & Nvmctrl::kProgE) != 0);
  CHECK(intflag() == (Nvmctrl::kReady | Nvmctrl::kError));
  nvm.write(Nvmctrl::kStatus, Nvmctrl::kProgE, 2);
  nvm.write(Nvmctrl::kIntFlag, Nvmctrl::kError, 1);
  CHECK((status() & Nvmctrl::kProgE) == 0);
  CHECK(intflag() == Nvmctrl::kReady);
  command(0x33);
  CHECK((status() & Nvmctrl::kProgE) != 0);
}

TEST_CASE_METHOD(Fixture, "the BOOTPROT section and locked regions refuse ER and WP with LOCKE") {
  nvm.load_flash(0x1000, {1, 2, 3, 4});
  command_at(Nvmctrl::kErase, 0x1000);
  CHECK((status() & Nvmctrl::kLockE) != 0);
  CHECK((intflag() & Nvmctrl::kError) != 0);
  CHECK(nvm.read_memory(0x1000, 4) == 0x04030201);
  nvm.write(Nvmctrl::kStatus, Nvmctrl::kLockE, 2);
  nvm.write(Nvmctrl::kIntFlag, Nvmctrl::kError, 1);

  command_at(Nvmctrl::kLockRegion, 0x8000);  // region 2: 0x8000-0xBFFF
  CHECK(nvm.read(Nvmctrl::kLock, 2) == 0xFFFB);
  nvm.load_flash(0x9000, {0, 0, 0, 0});
  command_at(Nvmctrl::kErase, 0x9000);
  CHECK((status() & Nvmctrl::kLockE) != 0);
  CHECK(nvm.read_memory(0x9000, 4) == 0);
  command_at(Nvmctrl::kUnlockRegion, 0xBFFE);
  CHECK(nvm.read(Nvmctrl::kLock, 2) == 0xFFFF);
  command_at(Nvmctrl::kErase, 0x9000);
  CHECK(nvm.read_memory(0x9000, 4) == 0xFFFFFFFF);
}

TEST_CASE_METHOD(Fixture, "the user row: EAR and WAP rewrite it; LOCK comes from it at reset") {
  CHECK(nvm.read_memory(Nvmctrl::kUserRow, 4) == 0xD8E0C7FA);
  nvm.write(Nvmctrl::kCtrlB, Nvmctrl::kManw, 4);
  command_at(Nvmctrl::kEraseAux, Nvmctrl::kUserRow);
  CHECK(nvm.read_memory(Nvmctrl::kUserRow, 4) == 0xFFFFFFFF);
  nvm.write_memory(Nvmctrl::kUserRow, 0xD8E0C7FF, 4);
  nvm.write_memory(Nvmctrl::kUserRow + 4, 0x7FFFFC5D, 4);  // region 15 locked
  command_at(Nvmctrl::kWriteAuxPage, Nvmctrl::kUserRow);
  CHECK(nvm.boot_section_size() == 0);
  CHECK(nvm.read(Nvmctrl::kLock, 2) == 0xFFFF);  // until the reset
  nvm.reset();
  CHECK(nvm.read(Nvmctrl::kLock, 2) == 0x7FFF);
  CHECK(violations.empty());
}

TEST_CASE_METHOD(Fixture, "the calibration row and serial number read as the firmware expects") {
  const uint32_t high = nvm.read_memory(Nvmctrl::kSoftwareCalibration + 4, 4);
  const uint32_t coarse = high >> 26;
  CHECK(coarse != 0x3F);
  CHECK(coarse == 0x1C);
  CHECK(nvm.read_memory(Nvmctrl::kSerialWord0, 4) != 0xFFFFFFFF);
  CHECK(Nvmctrl::in_nvm_space(Nvmctrl::kSerialWords123 + 8));
  CHECK_FALSE(Nvmctrl::in_nvm_space(0x40000));
}

TEST_CASE_METHOD(Fixture, "refused accesses are reported, not performed") {
  nvm.write_memory(0x2000, 0x12, 1);
  REQUIRE(violations.size() == 1);
  CHECK(violations[0].find("8-bit write to the page buffer at 0x00002000") != std::string::npos);
  nvm.write_memory(Nvmctrl::kCalibrationArea, 0, 4);
  CHECK(violations.size() == 2);
  nvm.write(Nvmctrl::kCtrlA, 0x02, 1);
  CHECK(violations.size() == 3);
  CHECK((status() & Nvmctrl::kProgE) != 0);
  command_at(Nvmctrl::kErase, 0x40000);
  CHECK(violations.size() == 4);
  CHECK_FALSE(nvm.load_flash(0x3FFFF, {1, 2}));
}

}  // namespace
}  // namespace hmc::emu
