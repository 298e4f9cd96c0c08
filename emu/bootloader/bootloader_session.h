// The bootloader's run: the SAM-BA monitor on the native USB port and/or the UF2 drive, over the
// chip's memory map (bare_chip.h), until the bootloader would start the application. Shared by
// hmc-emu (which then boots what the flash holds) and hmc-emu-bootloader.
#pragma once

#include <csignal>
#include <functional>
#include <string>

#include "bare_chip.h"

namespace hmc::emu {

struct BootloaderPorts {
  bool usb = false;
  std::string usb_link;        // a symbolic link naming the USB port ("": none)
  std::string uf2_drive;       // the drive's directory ("": none)
  bool touch_to_enter = false; // start as an application's USB port; a 1200-baud touch enters
};

enum class BootloaderEnd {
  kStartApplication,  // reset (AIRCR SYSRESETREQ) or a UF2 file written, and an application is there
  kStopped,           // `stop` was set
  kError,             // a port could not be made: `error` says why
};

// Runs until the bootloader ends. After a reset it starts the application unless the
// application's reset vector (0x2004) reads erased (0xFFFFFFFF): then, as the Arduino bootloader
// does, it stays in the bootloader. `say` receives one line per event.
BootloaderEnd run_bootloader(BareChip& chip, const BootloaderPorts& ports, const volatile std::sig_atomic_t& stop,
                             const std::function<void(const std::string&)>& say, std::string& error);

}  // namespace hmc::emu
