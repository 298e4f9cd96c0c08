// NVMCTRL and the NVM: each rule names the passage of the SAMD21 datasheet (chapter "NVMCTRL –
// Non-Volatile Memory Controller", unless said otherwise) it follows.
#include "nvmctrl.h"

#include <algorithm>
#include <cstdio>

namespace hmc::emu {
namespace {

std::string hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

bool in(uint32_t address, uint32_t base, uint32_t size) { return address >= base && address - base < size; }

// The NVM user row as the Arduino and UF2 bootloaders leave it: the factory value (word 0
// 0xD8E0C7FF, word 1 0xFFFFFC5D, as commonly reported for SAMD21 parts; a guess, not measured
// here) with BOOTPROT (bits 2:0) = 0x2, the 8 KB boot section those bootloaders set. Word 1
// bits 31:16 are the LOCK bits, all 1 = every region unlocked.
constexpr uint32_t kUserRowWord0 = 0xD8E0C7FA;
constexpr uint32_t kUserRowWord1 = 0xFFFFFC5D;

// The software calibration words at 0x806020 ("NVM Software Calibration Area Mapping"): ADC
// LINEARITY bits 34:27, ADC BIASCAL 37:35, OSC32K CAL 44:38, USB TRANSN 49:45, USB TRANSP 54:50,
// USB TRIM 57:55, DFLL48M COARSE CAL 63:58, DFLL48M FINE CAL 73:64. Every part has its own
// values; these are a guess in the range real parts report, chosen so that no field reads as
// erased (COARSE 0x3F means "not calibrated" to the Arduino startup code).
constexpr uint64_t kCalibrationLow = (uint64_t{0x1C} << 58) | (uint64_t{0x5} << 55) | (uint64_t{0x1D} << 50) |
                                     (uint64_t{0x05} << 45) | (uint64_t{0x40} << 38) | (uint64_t{0x7} << 35) |
                                     (uint64_t{0x3A} << 27);
constexpr uint32_t kCalibrationFine = 0x200;
// The 128-bit serial number ("Serial Number"): the emulator's own.
constexpr uint32_t kSerial[4] = {0x454D5530, 0x484D4321, 0x20534144, 0x32314731};

void put32(std::vector<uint8_t>& bytes, uint32_t at, uint32_t v) {
  for (unsigned i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(v >> (8 * i));
}

uint32_t get(const std::vector<uint8_t>& bytes, uint32_t at, unsigned size) {
  uint32_t v = 0;
  for (unsigned i = 0; i < size; ++i) v |= static_cast<uint32_t>(bytes[at + i]) << (8 * i);
  return v;
}

}  // namespace

Nvmctrl::Nvmctrl(std::function<void(const std::string&)> violation)
    : violation_(std::move(violation)),
      flash_(kFlashSize, 0xFF),
      user_row_(kRowSize, 0xFF),
      calibration_row_(kRowSize, 0xFF),
      page_buffer_(kPageSize, 0xFF) {
  put32(user_row_, 0, kUserRowWord0);
  put32(user_row_, 4, kUserRowWord1);
  put32(calibration_row_, kSoftwareCalibration - kCalibrationArea, static_cast<uint32_t>(kCalibrationLow));
  put32(calibration_row_, kSoftwareCalibration - kCalibrationArea + 4, static_cast<uint32_t>(kCalibrationLow >> 32));
  put32(calibration_row_, kSoftwareCalibration - kCalibrationArea + 8, 0xFFFFFC00 | kCalibrationFine);
  reset();
}

void Nvmctrl::reset() {
  // "Default value of MANW in NVM.CTRLB is 0" (SAMD21 errata, NVMCTRL), RWS 0, cache on.
  ctrlb_ = 0;
  addr_ = 0;
  inten_ = 0;
  error_flag_ = false;
  // STATUS.SB survives: the security bit is kept in the NVM ("Security Bit").
  status_ = static_cast<uint16_t>(status_ & kSecurityBit);
  // LOCK: "loaded from the NVM User Row at reset" (register LOCK, and "NVM User Row Mapping":
  // LOCK = bits 63:48).
  lock_ = static_cast<uint16_t>(get(user_row_, 6, 2));
  std::fill(page_buffer_.begin(), page_buffer_.end(), uint8_t{0xFF});
}

void Nvmctrl::report(const std::string& what) const {
  if (violation_) violation_("NVMCTRL: " + what);
}

uint32_t Nvmctrl::boot_section_size() const {
  // "Boot Loader Size": BOOTPROT 0x7 → 0 rows, 0x6 → 2, 0x5 → 4, ... 0x0 → 128 rows.
  const uint32_t bootprot = user_row_[0] & 0x7u;
  return bootprot == 7 ? 0 : kRowSize * (2u << (6 - bootprot));
}

bool Nvmctrl::address_locked(uint32_t byte_address) const {
  if (byte_address < boot_section_size()) return true;
  const uint32_t region = byte_address / kLockRegionSize;
  return (lock_ & (1u << region)) == 0;  // LOCK: 0 = locked
}

uint8_t Nvmctrl::intflag() const {
  // Commands complete at once here, so READY always reads 1: "INTFLAG.READY ... set when the NVM
  // controller is ready to accept a new command".
  return static_cast<uint8_t>(kReady | (error_flag_ ? kError : 0));
}

uint32_t Nvmctrl::read(uint32_t offset, unsigned size) {
  uint32_t word = 0;
  const uint32_t base = offset & ~3u;
  switch (base) {
    case kCtrlA: word = 0; break;  // the command field reads back 0 once executed
    case kCtrlB: word = ctrlb_; break;
    // PARAM: NVMP = number of pages, PSZ = 3 (64 bytes).
    case kParam: word = kPages | (3u << 16); break;
    case kIntEnClr:
    case kIntEnSet: word = inten_; break;
    case kIntFlag: word = intflag(); break;
    case kStatus: word = status_; break;
    case kAddr: word = addr_; break;
    case kLock: word = lock_; break;
    default: report("read of reserved offset " + hex(offset)); return 0;
  }
  const uint32_t shift = 8 * (offset & 3u);
  const uint32_t mask = size >= 4 ? 0xFFFFFFFFu : (1u << (8 * size)) - 1;
  return (word >> shift) & mask;
}

void Nvmctrl::write(uint32_t offset, uint32_t value, unsigned size) {
  const uint32_t base = offset & ~3u;
  const uint32_t shift = 8 * (offset & 3u);
  const uint32_t v = value << shift;
  const uint32_t mask = (size >= 4 ? 0xFFFFFFFFu : (1u << (8 * size)) - 1) << shift;
  switch (base) {
    case kCtrlA:
      // "To issue a command, the CTRLA.CMD bits must be written along with the CTRLA.CMDEX value"
      // in one write: a 16-bit (or wider) access carrying both.
      if ((mask & 0xFFFF) != 0xFFFF) {
        report("CTRLA written " + std::to_string(size) + " byte(s) at a time: CMD and CMDEX go in one write");
        status_ |= kProgE;
        error_flag_ = true;
        return;
      }
      // "PROGE ... set when an invalid command and/or a bad keyword was written in CTRLA".
      if (((v >> 8) & 0xFF) != kCmdExKey) {
        status_ |= kProgE;
        error_flag_ = true;
        return;
      }
      execute(static_cast<uint8_t>(v & 0x7F));
      return;
    case kCtrlB: {
      // RWS 4:1, MANW 7, SLEEPPRM 9:8, READMODE 17:16, CACHEDIS 18; the rest reserved.
      constexpr uint32_t writable = (0xFu << 1) | kManw | (3u << 8) | (3u << 16) | (1u << 18);
      ctrlb_ = (ctrlb_ & ~(mask & writable)) | (v & mask & writable);
      return;
    }
    case kParam: report("write to PARAM, which is read-only"); return;
    // "Writing a one to a bit in INTENCLR/INTENSET clears/sets the corresponding enable".
    case kIntEnClr: inten_ = static_cast<uint8_t>(inten_ & ~(v & mask & 3u)); return;
    case kIntEnSet: inten_ = static_cast<uint8_t>(inten_ | (v & mask & 3u)); return;
    case kIntFlag:
      // "Writing a one to INTFLAG.ERROR clears it"; READY cannot be cleared by software.
      if ((v & mask & kError) != 0) error_flag_ = false;
      return;
    case kStatus:
      // PROGE, LOCKE and NVME: "writing a one to this bit clears it"; LOAD, PRM, SB read-only.
      status_ = static_cast<uint16_t>(status_ & ~(v & mask & (kProgE | kLockE | kNvmE)));
      return;
    case kAddr:
      // ADDR[21:0]: "the hardware (16-bit) address to the NVM when a command is executed".
      addr_ = (addr_ & ~mask) | (v & mask);
      addr_ &= 0x3FFFFF;
      return;
    case kLock: report("write to LOCK: regions are locked and unlocked by the LR and UR commands"); return;
    default: report("write to reserved offset " + hex(offset)); return;
  }
}

bool Nvmctrl::in_nvm_space(uint32_t address) {
  return in(address, 0, kFlashSize) || in(address, kUserRow, kRowSize) || in(address, kCalibrationArea, kRowSize) ||
         in(address, kSerialWord0, 4) || in(address, kSerialWords123, 12);
}

uint32_t Nvmctrl::read_memory(uint32_t address, unsigned size) const {
  // "Reading from the NVM main address space is performed via the AHB bus by addressing the NVM
  // main address space or auxiliary address space directly."
  if (in(address, 0, kFlashSize)) return get(flash_, address, size);
  if (in(address, kUserRow, kRowSize)) return get(user_row_, address - kUserRow, size);
  if (in(address, kCalibrationArea, kRowSize)) return get(calibration_row_, address - kCalibrationArea, size);
  std::vector<uint8_t> serial(16);
  for (uint32_t i = 0; i < 4; ++i) put32(serial, 4 * i, kSerial[i]);
  if (in(address, kSerialWord0, 4)) return get(serial, address - kSerialWord0, size);
  if (in(address, kSerialWords123, 12)) return get(serial, 4 + address - kSerialWords123, size);
  report("read outside the NVM at " + hex(address));
  return 0;
}

void Nvmctrl::write_memory(uint32_t address, uint32_t value, unsigned size) {
  const bool main_array = in(address, 0, kFlashSize);
  if (!main_array && !in(address, kUserRow, kRowSize)) {
    report("write to " + hex(address) + ", which is not the flash or the user row");
    return;
  }
  // "8-bit writes to the page buffer are not allowed, and will cause a system exception."
  if (size == 1) {
    report("8-bit write to the page buffer at " + hex(address) + " (only 16- and 32-bit writes are allowed)");
    return;
  }
  // "The page buffer is loaded by writing to the NVM main address space or auxiliary space ...
  // writing to the page buffer updates the ADDR register" (NVM Write); STATUS.LOAD says the buffer
  // holds data not yet written.
  const uint32_t in_page = address % kPageSize;
  for (unsigned i = 0; i < size; ++i) page_buffer_[in_page + i] = static_cast<uint8_t>(value >> (8 * i));
  addr_ = (address / 2) & 0x3FFFFF;
  status_ |= kLoad;
  // "Automatic page write (CTRLB.MANW = 0): ... a write to the last word of the page buffer
  // triggers a page write" to the page ADDR holds.
  if ((ctrlb_ & kManw) == 0 && in_page + size == kPageSize) execute(main_array ? kWritePage : kWriteAuxPage);
}

void Nvmctrl::program_page(std::vector<uint8_t>& array, uint32_t offset) {
  // Flash programming can only change bits from 1 to 0 ("an erase must be done before
  // programming"; erasing sets all bits to 1): the page becomes old AND new.
  for (uint32_t i = 0; i < kPageSize; ++i) array[offset + i] &= page_buffer_[i];
  // "The page buffer is automatically set to all 1 after a page write is performed."
  std::fill(page_buffer_.begin(), page_buffer_.end(), uint8_t{0xFF});
  status_ = static_cast<uint16_t>(status_ & ~kLoad);
}

void Nvmctrl::execute(uint8_t command) {
  const uint32_t byte_address = addr_ * 2;
  auto fail = [this](uint16_t bit) {
    status_ |= bit;
    error_flag_ = true;  // "ERROR: set when one of STATUS.PROGE, LOCKE or NVME is set"
  };
  switch (command) {
    case kErase:
    case kWritePage:
      if (!in(byte_address, 0, kFlashSize)) {
        report((command == kErase ? std::string("ER") : std::string("WP")) + " with ADDR " + hex(addr_) +
               " (byte " + hex(byte_address) + ") outside the main array");
        fail(kProgE);
        return;
      }
      // "If the row resides in a region that is locked, the erase/write will not be performed and
      // the Lock Error bit in the Status register (STATUS.LOCKE) will be set"; the BOOTPROT boot
      // section is protected the same way ("Boot Loader Size").
      if (address_locked(byte_address)) {
        fail(kLockE);
        return;
      }
      if (command == kErase) {
        const uint32_t row = byte_address / kRowSize * kRowSize;
        std::fill(flash_.begin() + row, flash_.begin() + row + kRowSize, uint8_t{0xFF});
      } else {
        program_page(flash_, byte_address / kPageSize * kPageSize);
      }
      return;
    case kEraseAux:
    case kWriteAuxPage:
      // EAR/WAP act on "the auxiliary row addressed by the ADDR register" and may be given "only
      // to the user configuration row". ADDR holds 22 bits of a word address, so 0x804000 / 2
      // keeps only its offset inside the row; the command itself selects the auxiliary space.
      if (command == kEraseAux)
        std::fill(user_row_.begin(), user_row_.end(), uint8_t{0xFF});
      else
        program_page(user_row_, byte_address % kRowSize / kPageSize * kPageSize);
      return;
    case kLockRegion:
    case kUnlockRegion: {
      // "Lock/Unlock Region: locks/unlocks the region containing the address in ADDR"; the user
      // row's bits are untouched, so the lock state goes back to them at the next reset.
      if (!in(byte_address, 0, kFlashSize)) {
        fail(kProgE);
        return;
      }
      const uint16_t bit = static_cast<uint16_t>(1u << (byte_address / kLockRegionSize));
      lock_ = command == kLockRegion ? static_cast<uint16_t>(lock_ & ~bit) : static_cast<uint16_t>(lock_ | bit);
      return;
    }
    case kPageBufferClear:
      // "Page Buffer Clear: clears the page buffer" (all bits 1).
      std::fill(page_buffer_.begin(), page_buffer_.end(), uint8_t{0xFF});
      status_ = static_cast<uint16_t>(status_ & ~kLoad);
      return;
    case kSetSecurityBit: status_ |= kSecurityBit; return;
    case kSetPowerReduction: status_ |= kPrm; return;
    case kClearPowerReduction: status_ = static_cast<uint16_t>(status_ & ~kPrm); return;
    case kInvalidateCache: return;  // no cache contents are modelled
    case kSecurityFlow:
    case kWriteLockbits:
      report("command " + hex(command) + " is for factory use and not modelled");
      fail(kProgE);
      return;
    default: fail(kProgE); return;  // "an invalid command ... was written in CTRLA"
  }
}

bool Nvmctrl::load_flash(uint32_t address, const std::vector<uint8_t>& bytes) {
  if (address > kFlashSize || bytes.size() > kFlashSize - address) return false;
  std::copy(bytes.begin(), bytes.end(), flash_.begin() + address);
  return true;
}

void Nvmctrl::set_user_row(const std::vector<uint8_t>& row) {
  std::fill(user_row_.begin(), user_row_.end(), uint8_t{0xFF});
  std::copy_n(row.begin(), std::min<size_t>(row.size(), user_row_.size()), user_row_.begin());
  lock_ = static_cast<uint16_t>(get(user_row_, 6, 2));
}

}  // namespace hmc::emu
