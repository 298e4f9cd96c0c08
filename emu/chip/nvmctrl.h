// The SAMD21G18A's non-volatile memory and its controller, NVMCTRL (datasheet chapter "NVMCTRL –
// Non-Volatile Memory Controller", register facts checked against Microchip's register
// description): 256 KB of flash in 4096 pages of 64 bytes, erased a row (4 pages) at a time and
// written a page at a time through the page buffer, which is filled by writing to the flash
// address space; the NVM user row (fuses: boot protection, lock bits) and the factory's software
// calibration row, which the firmware reads.
//
// Two faces: the registers at 0x41004000 (the Peripheral interface, offsets from that base) and
// the NVM address space (read_memory/write_memory, absolute addresses: the flash at 0x0, the
// user row at 0x804000, the calibration area at 0x806000, the serial number words at 0x80A00C..).
// Host code (the image loader, the UF2 drive, tests) reads and loads the flash directly.
//
// What is modelled, each rule with the datasheet passage it follows in the .cpp: CTRLA commands
// with the CMDEX key (ER, WP, EAR, WAP, LR, UR, PBC, SSB, SPRM/CPRM, INVALL), INTFLAG READY/ERROR,
// STATUS PROGE/LOCKE/NVME/LOAD/SB and their clearing, ADDR in 16-bit words (updated by page
// buffer writes), PARAM (NVMP = 4096, PSZ = 64 bytes), CTRLB (RWS, MANW and the automatic page
// write when MANW is 0), LOCK regions and the BOOTPROT boot section, programming that can only
// clear bits (a write without an erase ANDs). Not modelled: programming and erase times (commands
// complete at once and READY never reads 0), the cache and the read wait states' timing (RWS,
// READMODE and CACHEDIS are stored; the CPU's cycle model charges them, emu/cpu/cpu.h), the EEPROM emulation area's fuse, the security bit's effect
// on a debugger.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "peripheral.h"

namespace hmc::emu {

class Nvmctrl : public Peripheral {
public:
  // Geometry (datasheet, NVMCTRL "Memory Organization"; the NVM Parameter register PARAM).
  static constexpr uint32_t kBase = 0x41004000;
  static constexpr uint32_t kPageSize = 64;
  static constexpr uint32_t kPagesPerRow = 4;
  static constexpr uint32_t kRowSize = kPageSize * kPagesPerRow;
  static constexpr uint32_t kPages = 4096;
  static constexpr uint32_t kFlashSize = kPages * kPageSize;  // 256 KB
  static constexpr uint32_t kLockRegions = 16;
  static constexpr uint32_t kLockRegionSize = kFlashSize / kLockRegions;  // 16 KB
  // The NVM rows outside the main array (datasheet, "NVM User Row Mapping", "NVM Software
  // Calibration Area Mapping", "Serial Number").
  static constexpr uint32_t kUserRow = 0x00804000;
  static constexpr uint32_t kCalibrationArea = 0x00806000;  // the row holding the calibration words
  static constexpr uint32_t kSoftwareCalibration = 0x00806020;
  static constexpr uint32_t kSerialWord0 = 0x0080A00C;
  static constexpr uint32_t kSerialWords123 = 0x0080A040;

  // Register offsets and bits (register description: NVMCTRL).
  static constexpr uint32_t kCtrlA = 0x00, kCtrlB = 0x04, kParam = 0x08, kIntEnClr = 0x0C,
                            kIntEnSet = 0x10, kIntFlag = 0x14, kStatus = 0x18, kAddr = 0x1C,
                            kLock = 0x20;
  static constexpr uint32_t kCmdExKey = 0xA5;
  enum Command : uint8_t {
    kErase = 0x02,         // ER: erase the row addressed by ADDR
    kWritePage = 0x04,     // WP
    kEraseAux = 0x05,      // EAR: the auxiliary (user) row
    kWriteAuxPage = 0x06,  // WAP
    kSecurityFlow = 0x0A,  // SF (factory use)
    kWriteLockbits = 0x0F, // WL (factory use)
    kLockRegion = 0x40,    // LR
    kUnlockRegion = 0x41,  // UR
    kSetPowerReduction = 0x42,
    kClearPowerReduction = 0x43,
    kPageBufferClear = 0x44,  // PBC
    kSetSecurityBit = 0x45,   // SSB
    kInvalidateCache = 0x46,  // INVALL
  };
  static constexpr uint8_t kReady = 1u << 0, kError = 1u << 1;  // INTFLAG / INTEN
  static constexpr uint16_t kPrm = 1u << 0, kLoad = 1u << 1, kProgE = 1u << 2, kLockE = 1u << 3,
                            kNvmE = 1u << 4, kSecurityBit = 1u << 8;  // STATUS
  static constexpr uint32_t kManw = 1u << 7;                          // CTRLB

  // `violation` receives a one-line description of each access the chip would refuse (an 8-bit
  // write to the page buffer, a write outside the NVM); it may be empty.
  explicit Nvmctrl(std::function<void(const std::string&)> violation = {});

  uint32_t read(uint32_t offset, unsigned size) override;
  void write(uint32_t offset, uint32_t value, unsigned size) override;

  // The NVM address space, as the CPU and the bus masters see it.
  static bool in_nvm_space(uint32_t address);
  uint32_t read_memory(uint32_t address, unsigned size) const;
  void write_memory(uint32_t address, uint32_t value, unsigned size);

  // A system reset: registers to their reset values, LOCK loaded from the user row's lock bits,
  // the page buffer lost; the NVM keeps its contents.
  void reset();

  // Host access, no controller rules: the flash (erased = 0xFF), the user row. load_flash
  // returns false (and changes nothing) when the bytes do not fit in the flash from `address`.
  const std::vector<uint8_t>& flash() const { return flash_; }
  bool load_flash(uint32_t address, const std::vector<uint8_t>& bytes);
  const std::vector<uint8_t>& user_row() const { return user_row_; }
  void set_user_row(const std::vector<uint8_t>& row);

  // Bytes protected by BOOTPROT (user row bits 2:0; datasheet, "Boot Loader Size" table).
  uint32_t boot_section_size() const;
  uint32_t read_wait_states() const { return (ctrlb_ >> 1) & 0xF; }
  // CTRLB.READMODE: 0 NO_MISS_PENALTY, 1 LOW_POWER, 2 DETERMINISTIC; CTRLB.CACHEDIS.
  uint32_t read_mode() const { return (ctrlb_ >> 16) & 3; }
  bool cache_disabled() const { return ((ctrlb_ >> 18) & 1) != 0; }
  bool interrupt_pending() const { return (intflag() & inten_) != 0; }

private:
  uint8_t intflag() const;
  void execute(uint8_t command);
  bool address_locked(uint32_t byte_address) const;
  void program_page(std::vector<uint8_t>& array, uint32_t offset);
  void report(const std::string& what) const;

  std::function<void(const std::string&)> violation_;
  std::vector<uint8_t> flash_;
  std::vector<uint8_t> user_row_;
  std::vector<uint8_t> calibration_row_;
  std::vector<uint8_t> page_buffer_;
  uint32_t ctrlb_ = 0;
  uint32_t addr_ = 0;  // in 16-bit words
  uint16_t status_ = 0;
  uint16_t lock_ = 0xFFFF;
  uint8_t inten_ = 0;
  bool error_flag_ = false;
};

}  // namespace hmc::emu
