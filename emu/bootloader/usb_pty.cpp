// The native USB port as a pseudo-terminal (usb_pty.h).
#include "usb_pty.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace hmc::emu {

UsbPty::~UsbPty() { close(); }

bool UsbPty::open(const std::string& link, std::string& error) {
  close();
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  char name[128];
  if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0 || ptsname_r(master_, name, sizeof name) != 0) {
    error = std::string("cannot create a pseudo-terminal: ") + std::strerror(errno);
    close();
    return false;
  }
  path_ = name;
  terminal_ = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  termios modes{};
  if (terminal_ < 0 || tcgetattr(terminal_, &modes) != 0) {
    error = "cannot open " + path_ + ": " + std::strerror(errno);
    close();
    return false;
  }
  // Raw until the host program sets its own modes: a USB CDC port passes bytes untouched.
  cfmakeraw(&modes);
  cfsetspeed(&modes, B115200);
  tcsetattr(terminal_, TCSANOW, &modes);
  fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
  if (!link.empty()) {
    struct stat st {};
    if (lstat(link.c_str(), &st) == 0) {
      if (!S_ISLNK(st.st_mode)) {
        error = "cannot name the USB port " + link + ": a file that is not a symbolic link is there";
        close();
        return false;
      }
      ::unlink(link.c_str());
    }
    if (symlink(path_.c_str(), link.c_str()) != 0) {
      error = "cannot create the link " + link + ": " + std::strerror(errno);
      close();
      return false;
    }
    link_ = link;
  }
  return true;
}

void UsbPty::close() {
  if (!link_.empty()) ::unlink(link_.c_str());
  link_.clear();
  if (terminal_ >= 0) ::close(terminal_);
  if (master_ >= 0) ::close(master_);
  terminal_ = master_ = -1;
  path_.clear();
}

bool UsbPty::touch_seen() {
  termios modes{};
  if (terminal_ < 0 || tcgetattr(terminal_, &modes) != 0) return false;
  if (cfgetospeed(&modes) != B1200) return false;
  // Seen: put the line back to a neutral speed so the next touch is a new event.
  cfsetspeed(&modes, B115200);
  tcsetattr(terminal_, TCSANOW, &modes);
  return true;
}

bool UsbPty::send(const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd p{master_, POLLOUT, 0};
      if (::poll(&p, 1, 1000) == 0) return false;  // nobody reads for a second: the host is gone
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace hmc::emu
