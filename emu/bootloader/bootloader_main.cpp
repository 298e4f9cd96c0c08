// hmc-emu-bootloader: a SAMD21 sitting in its bootloader, without the CPU: the SAM-BA monitor on a
// pseudo-terminal standing for the native USB port, and/or the UF2 drive as a directory, over the
// chip's NVM and NVMCTRL. It ends when the bootloader would start the application (bossac -R's
// reset, or a UF2 file taken), writing the flash to --flash-out. docs/emu.md, "Flashing".
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "bare_chip.h"
#include "samba_monitor.h"
#include "uf2_drive.h"
#include "usb_pty.h"

namespace {

constexpr const char* kUsage =
    "usage: hmc-emu-bootloader [--usb-pty[=LINK]] [--uf2-drive DIR] [--flash FILE] [--flash-out FILE]\n"
    "  --usb-pty[=LINK]  serve the SAM-BA monitor (bossac) on a pseudo-terminal; LINK names it\n"
    "  --uf2-drive DIR   present the UF2 drive in DIR and flash the .uf2 files copied there\n"
    "  --flash FILE      the flash's contents at start (a raw image from 0x0; default: erased)\n"
    "  --flash-out FILE  write the whole flash (256 KB) to FILE when the bootloader ends\n"
    "  --touch-to-enter  start as an application's USB serial port, which a 1200-baud touch turns\n"
    "                    into the bootloader's: the port leaves and comes back under LINK\n";

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void say(const std::string& line) { std::cerr << "hmc-emu-bootloader: " << line << std::endl; }

int usage_error(const std::string& what) {
  std::cerr << "hmc-emu-bootloader: error: " << what << "\n" << kUsage;
  return 2;
}

bool read_file(const std::string& path, std::vector<uint8_t>& bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

}  // namespace

int main(int argc, char** argv) {
  bool usb = false;
  bool touch_to_enter = false;
  std::string usb_link, drive, flash_in, flash_out;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& into) {
      if (i + 1 >= argc) return false;
      into = argv[++i];
      return true;
    };
    if (arg == "--usb-pty") {
      usb = true;
    } else if (arg.rfind("--usb-pty=", 0) == 0) {
      usb = true;
      usb_link = arg.substr(10);
    } else if (arg == "--uf2-drive") {
      if (!value(drive)) return usage_error("--uf2-drive needs a directory");
    } else if (arg == "--flash") {
      if (!value(flash_in)) return usage_error("--flash needs a file");
    } else if (arg == "--flash-out") {
      if (!value(flash_out)) return usage_error("--flash-out needs a file");
    } else if (arg == "--touch-to-enter") {
      touch_to_enter = true;
    } else if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return 0;
    } else {
      return usage_error("unknown argument '" + arg + "'");
    }
  }
  if (!usb && drive.empty()) return usage_error("give --usb-pty, --uf2-drive or both");
  if (touch_to_enter && usb_link.empty()) return usage_error("--touch-to-enter needs --usb-pty=LINK, the name that comes back");

  hmc::emu::BareChip chip;
  if (!flash_in.empty()) {
    std::vector<uint8_t> image;
    if (!read_file(flash_in, image)) {
      say("error: cannot read " + flash_in + ": " + std::strerror(errno));
      return 3;
    }
    if (!chip.nvm().load_flash(0, image)) {
      say("error: " + flash_in + " is " + std::to_string(image.size()) + " bytes, more than the 256 KB flash");
      return 1;
    }
  }
  hmc::emu::SambaMonitor monitor(chip, say);
  hmc::emu::UsbPty port;
  std::string error;
  if (usb) {
    if (!port.open(usb_link, error)) {
      say("error: " + error);
      return 3;
    }
    say("usb pty " + port.path() + (usb_link.empty() ? "" : " (" + usb_link + ")") +
        (touch_to_enter ? ": the application's port, waiting for a 1200-baud touch" : ""));
  }
  hmc::emu::Uf2Drive uf2(drive, chip, say);
  if (!drive.empty()) {
    if (!uf2.present(chip.nvm().flash(), error)) {
      say("error: " + error);
      return 3;
    }
    say("uf2 drive " + drive);
  }

  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  signal(SIGPIPE, SIG_IGN);
  const char* why = "stopped by a signal";
  bool in_application = touch_to_enter;
  while (g_stop == 0) {
    // The touch, as ArduinoCore-samd's USB serial port takes it: the application resets into the
    // bootloader, whose USB port enumerates afresh (on Linux, usually under the same name).
    if (in_application && port.touch_seen()) {
      say("1200-baud touch seen: the USB port leaves and comes back as the bootloader's");
      port.close();
      ::usleep(500 * 1000);
      if (!port.open(usb_link, error)) {
        say("error: " + error);
        return 3;
      }
      say("usb pty " + port.path() + " (" + usb_link + "): the bootloader's port");
      in_application = false;
    }
    pollfd p{port.fd(), POLLIN, 0};
    const int ready = ::poll(&p, usb ? 1 : 0, 100);
    if (ready < 0 && errno != EINTR) {
      say(std::string("error: poll: ") + std::strerror(errno));
      return 3;
    }
    if (ready > 0 && (p.revents & POLLIN) != 0) {
      uint8_t buffer[4096];
      const ssize_t n = ::read(port.fd(), buffer, sizeof buffer);
      if (n > 0 && !in_application && !port.send(monitor.receive(buffer, static_cast<size_t>(n))))
        say("the host stopped reading the USB port; answer dropped");
    }
    for (const std::string& v : chip.take_violations()) say(v);
    if (chip.reset_requested()) {
      why = "reset (AIRCR SYSRESETREQ): the bootloader would start the application now";
      break;
    }
    if (!drive.empty() && uf2.poll()) {
      why = "UF2 file flashed: the bootloader would start the application now";
      break;
    }
  }
  say(why);
  port.close();
  if (!flash_out.empty()) {
    std::ofstream out(flash_out, std::ios::binary | std::ios::trunc);
    const auto& flash = chip.nvm().flash();
    out.write(reinterpret_cast<const char*>(flash.data()), static_cast<std::streamsize>(flash.size()));
    if (!out) {
      say("error: cannot write " + flash_out);
      return 3;
    }
  }
  return 0;
}
