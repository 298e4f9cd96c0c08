// The bootloader's run (bootloader_session.h).
#include "bootloader_session.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "samba_monitor.h"
#include "uf2_drive.h"
#include "usb_pty.h"

namespace hmc::emu {
namespace {

constexpr uint32_t kAppResetVector = 0x2004;

}  // namespace

BootloaderEnd run_bootloader(BareChip& chip, const BootloaderPorts& ports, const volatile std::sig_atomic_t& stop,
                             const std::function<void(const std::string&)>& say, std::string& error) {
  if (ports.touch_to_enter && ports.usb_link.empty()) {
    error = "the 1200-baud touch needs the USB port named by a link (the name that comes back)";
    return BootloaderEnd::kError;
  }
  SambaMonitor monitor(chip, say);
  UsbPty port;
  if (ports.usb) {
    if (!port.open(ports.usb_link, error)) return BootloaderEnd::kError;
    say("usb pty " + port.path() + (ports.usb_link.empty() ? "" : " (" + ports.usb_link + ")") +
        (ports.touch_to_enter ? ": the application's port, waiting for a 1200-baud touch" : ""));
  }
  Uf2Drive uf2(ports.uf2_drive, chip, say);
  if (!ports.uf2_drive.empty()) {
    if (!uf2.present(chip.nvm().flash(), error)) return BootloaderEnd::kError;
    say("uf2 drive " + ports.uf2_drive);
  }
  bool in_application = ports.touch_to_enter;
  while (stop == 0) {
    // The touch, as ArduinoCore-samd's USB serial port takes it: the application resets into the
    // bootloader, whose USB port enumerates afresh (on Linux, usually under the same name).
    if (in_application && port.touch_seen()) {
      say("1200-baud touch seen: the USB port leaves and comes back as the bootloader's");
      port.close();
      ::usleep(500 * 1000);
      if (!port.open(ports.usb_link, error)) return BootloaderEnd::kError;
      say("usb pty " + port.path() + " (" + ports.usb_link + "): the bootloader's port");
      in_application = false;
    }
    pollfd p{port.fd(), POLLIN, 0};
    const int ready = ::poll(&p, ports.usb ? 1 : 0, 100);
    if (ready < 0 && errno != EINTR) {
      error = std::string("poll: ") + std::strerror(errno);
      return BootloaderEnd::kError;
    }
    if (ready > 0 && (p.revents & POLLIN) != 0) {
      uint8_t buffer[4096];
      const ssize_t n = ::read(port.fd(), buffer, sizeof buffer);
      if (n > 0 && !in_application && !port.send(monitor.receive(buffer, static_cast<size_t>(n))))
        say("the host stopped reading the USB port; answer dropped");
    }
    const bool flashed = !ports.uf2_drive.empty() && uf2.poll();
    if (!chip.reset_requested() && !flashed) continue;
    chip.clear_reset_request();
    const char* how = flashed ? "UF2 file written" : "reset (AIRCR SYSRESETREQ)";
    if (chip.nvm().read_memory(kAppResetVector, 4) == 0xFFFFFFFF) {
      say(std::string(how) + ": no application at 0x2000 (its reset vector reads erased): the bootloader stays");
      continue;
    }
    say(std::string(how) + ": the bootloader starts the application at 0x2000");
    return BootloaderEnd::kStartApplication;
  }
  return BootloaderEnd::kStopped;
}

}  // namespace hmc::emu
