// The serial ports this machine has (`hmc ports`), and which of them is likely the board.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hmc/result.h"

namespace hmc {

// The board talks through an FT232R(L) USB-serial bridge (HARDWARE.md, "SAMD21G18"), which
// enumerates with FTDI's default vendor and product IDs for the FT232R: 0403:6001. Any other
// adapter built on that chip has the same IDs, hence "likely".
inline constexpr int kBoardUsbVid = 0x0403;
inline constexpr int kBoardUsbPid = 0x6001;

struct PortInfo {
  std::string name;         // what to pass to --port: /dev/ttyUSB0
  std::string description;  // the system's words for it: "FT232R USB UART"
  std::string kind;         // "usb", "native", "bluetooth", or "virtual" for anything else
  std::string manufacturer;  // USB ports only; empty when unknown
  std::string product;
  std::string serial;
  int usb_vid = -1;  // -1 when not a USB port
  int usb_pid = -1;
  bool likely_board = false;  // an FT232R bridge (kBoardUsbVid:kBoardUsbPid)
};

// Every serial port the system reports, sorted by name. Pseudo-terminals are not listed.
Result<std::vector<PortInfo>> list_ports();

// The name of the one likely board among `ports`; nothing when there is none or more than one.
std::optional<std::string> find_board_port(const std::vector<PortInfo>& ports);

}  // namespace hmc
