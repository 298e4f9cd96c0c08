// The native USB CDC port as a pseudo-terminal: the host program (bossac, hmc) opens the
// terminal side, named by `path()` and, when asked, by a symbolic link; the emulator reads and
// writes the other side. The emulator keeps the terminal side open itself, so a host program
// closing and reopening it (as bossac does) does not hang up the line.
//
// The 1200-baud touch: `touch_seen()` says whether the terminal side was set to 1200 baud since
// the last call, read from its line settings (a pseudo-terminal carries no DTR line).
#pragma once

#include <string>

namespace hmc::emu {

class UsbPty {
public:
  UsbPty() = default;
  UsbPty(const UsbPty&) = delete;
  UsbPty& operator=(const UsbPty&) = delete;
  ~UsbPty();

  // Creates the pseudo-terminal; with a non-empty `link`, a symbolic link at that path names it
  // (an existing symbolic link there is replaced; any other file is an error).
  bool open(const std::string& link, std::string& error);
  // Removes the port (the link too), as a USB device that leaves the bus.
  void close();

  int fd() const { return master_; }
  const std::string& path() const { return path_; }
  // The name host programs use: the link if there is one, else the terminal's path.
  const std::string& name() const { return link_.empty() ? path_ : link_; }
  bool touch_seen();

  // Writes all of `bytes` (waiting while the terminal's buffer is full); false if the port is gone.
  bool send(const std::string& bytes);

private:
  int master_ = -1;
  int terminal_ = -1;  // our own handle on the terminal side
  std::string path_;
  std::string link_;
};

}  // namespace hmc::emu
