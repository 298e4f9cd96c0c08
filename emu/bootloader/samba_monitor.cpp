// The SAM-BA monitor: a command parser over the chip's bus (samba_monitor.h).
#include "samba_monitor.h"

#include <cstdio>

#include "nvmctrl.h"

namespace hmc::emu {
namespace {

std::string hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

// CRC-16/XMODEM, bit by bit: the checksum bossac compares the Z answer with.
uint16_t crc16_add(uint16_t crc, uint8_t byte) {
  crc = static_cast<uint16_t>(crc ^ (byte << 8));
  for (int bit = 0; bit < 8; ++bit)
    crc = static_cast<uint16_t>((crc & 0x8000) != 0 ? (crc << 1) ^ 0x1021 : crc << 1);
  return crc;
}

int hex_digit(uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

void put_le(std::string& out, uint32_t v, unsigned size) {
  for (unsigned i = 0; i < size; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}

}  // namespace

SambaMonitor::SambaMonitor(TargetBus& bus, std::function<void(const std::string&)> log,
                           std::function<bool(uint32_t)> go)
    : bus_(bus), flash_(bus), log_(std::move(log)), go_(std::move(go)) {}

void SambaMonitor::fail(const std::string& what) {
  if (log_) log_(what);
}

bool SambaMonitor::read(uint32_t address, unsigned size, uint32_t& value) {
  std::string error;
  if (bus_.read(address, size, value, error)) return true;
  fail("bootloader: " + error);
  value = 0;
  return false;
}

bool SambaMonitor::write(uint32_t address, uint32_t value, unsigned size) {
  std::string error;
  if (bus_.write(address, value, size, error)) return true;
  fail("bootloader: " + error);
  return false;
}

std::string SambaMonitor::receive(const uint8_t* data, size_t size) {
  std::string out;
  for (size_t i = 0; i < size; ++i) {
    const uint8_t c = data[i];
    if (receive_left_ > 0) {  // the binary payload of an S command
      write(receive_at_++, c, 1);
      --receive_left_;
      continue;
    }
    if (c == '#') {
      execute(command_, address_, number_, out);
      command_ = 0;
      number_ = 0;
      address_ = 0;
      continue;
    }
    const int digit = hex_digit(c);
    if (digit >= 0) {
      number_ = number_ << 4 | static_cast<uint32_t>(digit);
    } else if (c == ',') {
      address_ = number_;
      number_ = 0;
    } else if (c > ' ' && c < 0x7F) {
      command_ = static_cast<char>(c);
      number_ = 0;
    }  // anything else (line ends, the bytes bossac flushes with) is ignored
  }
  return out;
}

void SambaMonitor::execute(char command, uint32_t address, uint32_t number, std::string& out) {
  // A one-argument command ("GADDR#", "XADDR#") has its argument in `number`.
  switch (command) {
    case 0: return;  // a lone '#' (RS-232 auto-baud ends with one): no command
    case 'N': out += "\n\r"; return;
    case 'V': out += std::string(kVersion) + "\n\r"; return;
    case 'w':
    case 'h':
    case 'o': {
      const unsigned size = command == 'w' ? 4 : command == 'h' ? 2 : 1;
      uint32_t value = 0;
      read(address, size, value);
      put_le(out, value, size);
      return;
    }
    case 'W': write(address, number, 4); return;
    case 'H': write(address, number & 0xFFFF, 2); return;
    case 'O': write(address, number & 0xFF, 1); return;
    case 'S':
      receive_at_ = address;
      receive_left_ = number;
      return;
    case 'R':
      for (uint32_t i = 0; i < number; ++i) {
        uint32_t value = 0;
        read(address + i, 1, value);
        out += static_cast<char>(value);
      }
      return;
    case 'G':
      if (!go_ || !go_(number)) fail("bootloader: G" + hex(number) + ": running code needs the emulated CPU");
      return;
    case 'X':
      erase_from(number);
      out += "X\n\r";
      return;
    case 'Y':
      if (number == 0)
        source_buffer_ = address;
      else
        write_flash(address, number);
      out += "Y\n\r";
      return;
    case 'Z': {
      uint16_t crc = 0;
      for (uint32_t i = 0; i < number; ++i) {
        uint32_t value = 0;
        read(address + i, 1, value);
        crc = crc16_add(crc, static_cast<uint8_t>(value));
      }
      char text[16];
      std::snprintf(text, sizeof text, "Z%08X#", crc);
      out += std::string(text) + "\n\r";
      return;
    }
    default: fail(std::string("bootloader: command '") + command + "' is not part of the monitor's USB protocol");
  }
}

void SambaMonitor::erase_from(uint32_t address) {
  if (address % Nvmctrl::kRowSize != 0) {
    fail("bootloader: X" + hex(address) + ": not the start of a row");
    return;
  }
  std::string error;
  for (uint32_t row = address; row < Nvmctrl::kFlashSize; row += Nvmctrl::kRowSize) {
    if (!flash_.erase_row(row, error)) {
      fail("bootloader: X" + hex(address) + ": " + error);
      return;
    }
  }
}

void SambaMonitor::write_flash(uint32_t destination, uint32_t size) {
  if (destination % Nvmctrl::kPageSize != 0 || size % Nvmctrl::kPageSize != 0) {
    fail("bootloader: Y" + hex(destination) + "," + hex(size) + ": not whole pages");
    return;
  }
  std::string error;
  for (uint32_t done = 0; done < size; done += Nvmctrl::kPageSize) {
    uint32_t words[Nvmctrl::kPageSize / 4];
    for (uint32_t i = 0; i < Nvmctrl::kPageSize / 4; ++i)
      if (!read(source_buffer_ + done + 4 * i, 4, words[i])) return;
    if (!flash_.write_page(destination + done, words, error)) {
      fail("bootloader: Y" + hex(destination) + "," + hex(size) + ": " + error);
      return;
    }
  }
}

}  // namespace hmc::emu
