// The SAM-BA monitor as the Arduino and UF2 SAMD21 bootloaders speak it on the native USB port,
// the protocol bossac drives. Commands are ASCII, end in '#', and take hexadecimal arguments
// ("W41004000,0000A502#"); bossac's own description of them (its Samba class) is the reference:
//
//   N#              binary mode; answers "\n\r"
//   V#              the version string; "[Arduino:XYZ]" in it tells bossac the X, Y, Z
//                   extensions below exist (without them it would run a copy applet with G)
//   wADDR,4#  hADDR,2#  oADDR,1#      read a word, half-word, byte: answered in binary, little-endian
//   WADDR,VALUE#  HADDR,VALUE#  OADDR,VALUE#   write one
//   SADDR,LEN#      the next LEN bytes go to memory from ADDR (binary, USB mode)
//   RADDR,LEN#      answers LEN bytes of memory from ADDR (binary, USB mode)
//   GADDR#          run the code whose vector table is at ADDR (needs the CPU: see `go`)
//   XADDR#          erase the flash from ADDR to its end; answers "X\n\r"
//   YADDR,0#        the source buffer for the next write is at ADDR; answers "Y\n\r"
//   YADDR,LEN#      write LEN bytes from the source buffer to the flash at ADDR; answers "Y\n\r"
//   ZADDR,LEN#      CRC-16 (CCITT, 0x1021, from 0) of memory; answers "Z%08X#\n\r"
//
// Every memory access the monitor makes goes through the chip (TargetBus): X and Y drive NVMCTRL
// the way a bootloader's code does (ER per row; page buffer clear, 32-bit writes into the page
// buffer, WP per page), so the controller's rules apply. RS-232 mode (auto-baud and XMODEM
// transfers for S and R) is not spoken: the bootloaders use it on their UART, not on USB.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "boot_flash.h"
#include "target_bus.h"

namespace hmc::emu {

class SambaMonitor {
public:
  // `log` receives one line per refused or failed command; `go` runs code at an address and
  // returns false when it cannot (no CPU attached). Either may be empty.
  SambaMonitor(TargetBus& bus, std::function<void(const std::string&)> log,
               std::function<bool(uint32_t)> go = {});

  // Takes bytes the host sent; returns the bytes the monitor answers with.
  std::string receive(const uint8_t* data, size_t size);

  static constexpr const char* kVersion = "v2.0 [Arduino:XYZ] hmc-emu";

private:
  void execute(char command, uint32_t address, uint32_t number, std::string& out);
  bool read(uint32_t address, unsigned size, uint32_t& value);
  bool write(uint32_t address, uint32_t value, unsigned size);
  void erase_from(uint32_t address);
  void write_flash(uint32_t destination, uint32_t size);
  void fail(const std::string& what);

  TargetBus& bus_;
  BootFlash flash_;
  std::function<void(const std::string&)> log_;
  std::function<bool(uint32_t)> go_;
  char command_ = 0;
  uint32_t number_ = 0;
  uint32_t address_ = 0;
  uint32_t receive_left_ = 0;  // bytes of an S transfer still to come
  uint32_t receive_at_ = 0;
  uint32_t source_buffer_ = 0;  // set by YADDR,0#
};

}  // namespace hmc::emu
