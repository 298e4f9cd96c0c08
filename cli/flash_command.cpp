// `hmc flash [FILE] [--method bossac|openocd|uf2]`: flash the SAMD21 firmware. Checks the image
// by its content and names the board variant it was built for (warning that the variant's
// guessed pins are unverified), then runs bossac or OpenOCD (fork/exec, no shell, their output
// passed through) or copies the UF2 file onto the bootloader's drive, and with --ver-port asks
// the restarted board's VER. `--dry-run` prints what it would do.
#include "flash_command.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "connection.h"
#include "exit_codes.h"
#include "hmc/session.h"
#include "hmc/transport.h"

namespace hmc::cli {
namespace {

namespace fs = std::filesystem;

// Facts from HARDWARE.md ("Flashing a SAMD21") and docs/firmware.md.
constexpr std::uint32_t kUf2Magic0 = 0x0A324655;
constexpr std::uint32_t kUf2Magic1 = 0x9E5D5157;
constexpr std::uint32_t kUf2MagicEnd = 0x0AB16F30;
constexpr std::uint32_t kUf2FlagFamily = 0x2000;
constexpr std::uint32_t kSamd21Family = 0x68ED2B88;
constexpr std::size_t kUf2Block = 512;
constexpr std::uint32_t kAppOffset = 0x2000;     // behind the 8 KB bootloader
constexpr std::uint32_t kFlashSize = 256 * 1024;  // SAMD21G18
constexpr const char* kFirmwareDir = "build/firmware/firmware/targets/samd21";
constexpr const char* kBuildHint = "cmake --preset firmware && cmake --build build/firmware";

struct FlashOptions {
  std::string file;
  std::string method = "bossac";
  std::string port;
  std::string drive;
  std::string offset_text;
  std::string probe = "cmsis-dap";
  std::string ver_port;
  double ver_wait_s = 10;
  bool dry_run = false;
  bool no_touch = false;
};

// Every refusal: an exit code and the message printed after "hmc flash: error: ".
struct Failure {
  int code;
  std::string message;
};

[[noreturn]] void fail(int code, const std::string& message) { throw Failure{code, message}; }

std::string hex(std::uint32_t v) {
  std::ostringstream out;
  out << "0x" << std::hex << std::uppercase << std::setw(8) << std::setfill('0') << v;
  return out.str();
}

// Offsets as they appear in commands: 0x2000, 0x0.
std::string offset_hex(std::uint32_t v) {
  std::ostringstream out;
  out << "0x" << std::hex << v;
  return out.str();
}

// One word, quoted for a POSIX shell only when it needs it.
std::string shell_quote(const std::string& word) {
  static const std::string safe =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_@%+=:,./-";
  if (!word.empty() && word.find_first_not_of(safe) == std::string::npos) return word;
  std::string out = "'";
  for (char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string shell_line(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) out += (out.empty() ? "" : " ") + shell_quote(a);
  return out;
}

// A path inside an OpenOCD (Tcl) command: braced when it holds anything Tcl would interpret.
std::string tcl_word(const std::string& word) {
  if (word.find_first_of("{}\\") != std::string::npos)
    fail(kExitUsage, "the path '" + word + "' holds a brace or backslash, which OpenOCD cannot take: rename it");
  if (word.find_first_of(" \t;$[]\"") == std::string::npos) return word;
  return "{" + word + "}";
}

std::optional<std::string> find_in_path(const std::string& tool) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    std::string dir = dirs.substr(start, end - start);
    if (dir.empty()) dir = ".";
    const std::string candidate = dir + "/" + tool;
    struct stat st {};
    if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(candidate.c_str(), X_OK) == 0)
      return candidate;
    start = end + 1;
  }
  return std::nullopt;
}

// --- the image ------------------------------------------------------------------------------

std::vector<unsigned char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(kExitIo, "cannot read '" + path + "': " + std::strerror(errno));
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(kExitIo, "cannot read '" + path + "'");
  return bytes;
}

std::uint32_t le32(const std::vector<unsigned char>& b, std::size_t at) {
  return static_cast<std::uint32_t>(b[at]) | static_cast<std::uint32_t>(b[at + 1]) << 8 |
         static_cast<std::uint32_t>(b[at + 2]) << 16 | static_cast<std::uint32_t>(b[at + 3]) << 24;
}

bool is_elf(const std::vector<unsigned char>& b) {
  return b.size() >= 4 && b[0] == 0x7F && b[1] == 'E' && b[2] == 'L' && b[3] == 'F';
}

bool is_uf2(const std::vector<unsigned char>& b) {
  return b.size() >= 8 && le32(b, 0) == kUf2Magic0 && le32(b, 4) == kUf2Magic1;
}

// The file next to `path` with another extension, for "use X instead" hints.
std::string sibling(const std::string& path, const std::string& ext) {
  return fs::path(path).replace_extension(ext).string();
}

// A raw image for bossac/OpenOCD: not an ELF or UF2, and a Cortex-M vector table whose reset
// vector lies inside the image as placed at `offset` (so an image linked for 0x0 is not written
// at 0x2000, or the other way round).
void check_raw_image(const std::string& path, const std::vector<unsigned char>& b, std::uint32_t offset) {
  if (is_elf(b))
    fail(kExitInvalid, "'" + path + "' is an ELF file, not a raw image: use the .bin made from it (" +
                           sibling(path, ".bin") + ")");
  if (is_uf2(b))
    fail(kExitInvalid, "'" + path + "' is a UF2 file, not a raw image: use --method uf2 for it, or the .bin (" +
                           sibling(path, ".bin") + ")");
  if (b.size() < 8) fail(kExitInvalid, "'" + path + "' is " + std::to_string(b.size()) + " bytes: too short for an image");
  if (b.size() > kFlashSize - offset)
    fail(kExitInvalid, "'" + path + "' is " + std::to_string(b.size()) + " bytes: more than the " +
                           std::to_string(kFlashSize - offset) + " bytes of flash from " + offset_hex(offset));
  const std::uint32_t reset = le32(b, 4) & ~1U;
  if (reset < offset || reset >= offset + b.size()) {
    std::string hint = offset == kAppOffset ? " (an image linked at 0x0, like hmc-firmware-nobl.bin, needs --method openocd --offset 0x0)"
                                            : " (an image linked at 0x2000, like hmc-firmware.bin, goes to --offset 0x2000)";
    fail(kExitInvalid, "'" + path + "' does not look linked for " + offset_hex(offset) + ": its reset vector " +
                           hex(reset) + " is outside " + hex(offset) + "-" +
                           hex(offset + static_cast<std::uint32_t>(b.size()) - 1) + hint);
  }
}

void check_uf2_image(const std::string& path, const std::vector<unsigned char>& b) {
  if (is_elf(b))
    fail(kExitInvalid, "'" + path + "' is an ELF file, not UF2: use the .uf2 (" + sibling(path, ".uf2") + ")");
  if (!is_uf2(b))
    fail(kExitInvalid, "'" + path + "' is not a UF2 file (no UF2 block magics " + hex(kUf2Magic0) + " " +
                           hex(kUf2Magic1) + " at its start): use the .uf2 (" + sibling(path, ".uf2") +
                           "), or make one with hmc-uf2 convert");
  if (b.size() < kUf2Block || b.size() % kUf2Block != 0)
    fail(kExitInvalid, "'" + path + "' is " + std::to_string(b.size()) + " bytes: not a whole number of 512-byte UF2 blocks");
  if (le32(b, kUf2Block - 4) != kUf2MagicEnd)
    fail(kExitInvalid, "'" + path + "': the first UF2 block's end magic is " + hex(le32(b, kUf2Block - 4)) +
                           ", not " + hex(kUf2MagicEnd));
  if ((le32(b, 8) & kUf2FlagFamily) == 0 || le32(b, 28) != kSamd21Family)
    fail(kExitInvalid, "'" + path + "' is not for the SAMD21: its first block's family id is " +
                           ((le32(b, 8) & kUf2FlagFamily) == 0 ? std::string("absent") : hex(le32(b, 28))) +
                           ", not " + hex(kSamd21Family));
}

// --- the board variant the image was built for ------------------------------------------------

// The image's board info text (firmware/targets/samd21/board_info.cpp):
// "hmc-board:<variant>;protocol:<n>;firmware:<n>;guessed:PA05,PA06,...;".
struct ImageInfo {
  std::string variant;
  std::optional<std::uint32_t> protocol;
  std::optional<std::uint32_t> firmware;
  std::vector<std::string> guessed;
};

// The flash contents a file holds: a raw image as it is, a UF2 file's payloads in block order.
std::vector<unsigned char> flash_bytes(const std::vector<unsigned char>& b) {
  if (!is_uf2(b)) return b;
  std::vector<unsigned char> out;
  for (std::size_t at = 0; at + kUf2Block <= b.size(); at += kUf2Block) {
    const std::uint32_t size = std::min<std::uint32_t>(le32(b, at + 16), 476);
    out.insert(out.end(), b.begin() + static_cast<std::ptrdiff_t>(at + 32),
               b.begin() + static_cast<std::ptrdiff_t>(at + 32 + size));
  }
  return out;
}

std::optional<ImageInfo> image_info(const std::vector<unsigned char>& file_bytes) {
  static const std::string kMarker = "hmc-board:";
  const std::vector<unsigned char> bytes = flash_bytes(file_bytes);
  const auto found = std::search(bytes.begin(), bytes.end(), kMarker.begin(), kMarker.end());
  if (found == bytes.end()) return std::nullopt;
  std::string text;
  for (auto it = found + static_cast<std::ptrdiff_t>(kMarker.size()); it != bytes.end() && *it != 0 && text.size() < 256; ++it) {
    text += static_cast<char>(*it);
  }
  ImageInfo info;
  std::istringstream fields(text);
  std::string field;
  std::getline(fields, info.variant, ';');
  while (std::getline(fields, field, ';')) {
    const auto colon = field.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = field.substr(0, colon);
    const std::string value = field.substr(colon + 1);
    const auto number = [&value]() -> std::optional<std::uint32_t> {
      if (value.empty() || value.size() > 9 || value.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
      return static_cast<std::uint32_t>(std::stoul(value));
    };
    if (key == "protocol") info.protocol = number();
    if (key == "firmware") info.firmware = number();
    if (key == "guessed") {
      std::istringstream pins(value);
      for (std::string pin; std::getline(pins, pin, ',');) {
        if (!pin.empty()) info.guessed.push_back(pin);
      }
    }
  }
  return info;
}

// Says which board variant the image expects and that its guessed pins are unverified.
void announce_image(const std::optional<ImageInfo>& info) {
  if (!info) {
    std::cerr << "hmc flash: note: the image names no board variant (built before board variants, or not this "
                 "project's firmware): its pin map is unknown\n";
    return;
  }
  std::cerr << "hmc flash: image for board variant '" << info->variant << "'";
  if (info->firmware && info->protocol) {
    std::cerr << ", firmware " << firmware_version_text(*info->firmware) << ", protocol " << *info->protocol;
  }
  std::cerr << "\n";
  if (!info->guessed.empty()) {
    std::string pins;
    for (const auto& pin : info->guessed) pins += (pins.empty() ? "" : ", ") + pin;
    std::cerr << "hmc flash: warning: " << info->guessed.size() << " pins of variant '" << info->variant
              << "' are guessed, not verified on a real board: " << pins
              << ". Check them against the board's wiring (docs/firmware.md, \"Pin map\") before connecting motor "
                 "power: a wrong pin can drive an output against another\n";
  }
}

// --- after writing: ask the board -----------------------------------------------------------

// Asks VER on `port` until the board answers or `wait_s` passes (the board restarts into the new
// image, and its UART port may take a moment). Returns the exit code.
int confirm_version(const std::string& port, double wait_s, const std::optional<ImageInfo>& info) {
  if (port.empty()) {
    std::cerr << "hmc flash: not confirmed: give --ver-port (the board's command port, e.g. /dev/ttyUSB0) to have "
                 "the restarted board's VER checked\n";
    return kExitOk;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long>(wait_s * 1000));
  std::string last_problem = "no attempt";
  do {
    Result<std::unique_ptr<Transport>> link = open_port(port);
    if (!link) {
      last_problem = link.error().message;
    } else {
      SessionOptions options;
      options.reply_timeout = std::chrono::milliseconds(500);
      auto session = Session::open(std::move(link.value()), options);
      if (!session) {
        last_problem = session.error().message;
      } else if (session.value()->firmware() == Firmware::kSeed || !session.value()->version()) {
        last_problem = "the board does not answer VER (the seed firmware, or not running yet)";
      } else {
        const Version& v = *session.value()->version();
        std::cerr << "hmc flash: the board on " << port << " answers VER: firmware " << firmware_version_text(v.firmware)
                  << ", protocol " << v.protocol << "\n";
        if (info && info->firmware && info->protocol && (v.firmware != *info->firmware || v.protocol != *info->protocol)) {
          std::cerr << "hmc flash: error: that is not the image just written (firmware "
                    << firmware_version_text(*info->firmware) << ", protocol " << *info->protocol << "): is " << port
                    << " this board's command port?\n";
          return kExitInvalid;
        }
        std::cerr << "hmc flash: confirmed: the board runs the new firmware\n";
        return kExitOk;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  } while (std::chrono::steady_clock::now() < deadline);
  std::cerr << "hmc flash: could not confirm the new firmware on " << port << " within " << wait_s << " s: " << last_problem
            << "\n";
  return kExitNoReply;
}

// --- the default file -----------------------------------------------------------------------

bool is_repository_root(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "CMakePresets.json", ec) && fs::is_directory(dir / "firmware/targets/samd21", ec);
}

std::optional<fs::path> root_above(fs::path dir) {
  for (; !dir.empty(); dir = dir.parent_path()) {
    if (is_repository_root(dir)) return dir;
    if (dir == dir.parent_path()) break;
  }
  return std::nullopt;
}

// The repository: above the executable (a build tree inside the checkout), else above the
// current directory.
std::optional<fs::path> repository_root(const fs::path& exe) {
  if (!exe.empty()) {
    if (auto root = root_above(exe.parent_path())) return root;
  }
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  if (!ec) return root_above(cwd);
  return std::nullopt;
}

// The images an installed hmc finds beside itself: <bindir>/HMC_FIRMWARE_FROM_BINDIR, where
// the hmc-firmware package (or `cmake --install` after the firmware preset) puts them.
std::optional<fs::path> installed_firmware_dir(const fs::path& exe) {
#ifdef HMC_FIRMWARE_FROM_BINDIR
  std::error_code ec;
  if (exe.empty()) return std::nullopt;
  const fs::path dir = (exe.parent_path() / HMC_FIRMWARE_FROM_BINDIR).lexically_normal();
  if (fs::is_directory(dir, ec)) return dir;
#else
  static_cast<void>(exe);
#endif
  return std::nullopt;
}

// A build tree inside the checkout uses the firmware preset's outputs; an installed hmc, the
// installed images.
std::string default_file(const std::string& method, std::uint32_t offset) {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) exe.clear();
  const std::string name = std::string(offset == 0 ? "hmc-firmware-nobl" : "hmc-firmware") +
                           (method == "uf2" ? ".uf2" : ".bin");
  const auto root = repository_root(exe);
  if (root) {
    const fs::path file = *root / kFirmwareDir / name;
    if (!fs::exists(file, ec))
      fail(kExitIo, "no FILE given, and the firmware is not built: " + file.string() + " does not exist (run: " +
                        kBuildHint + ", in " + root->string() + ")");
    return file.string();
  }
  if (const auto installed = installed_firmware_dir(exe)) {
    const fs::path file = *installed / name;
    if (!fs::exists(file, ec))
      fail(kExitIo, "no FILE given, and " + file.string() + " does not exist: reinstall the hmc-firmware package");
    return file.string();
  }
  fail(kExitIo, "no FILE given, no hmc repository above this executable or the current directory, and no "
                "installed firmware (the hmc-firmware package): give the image's path");
}

// --- the steps ------------------------------------------------------------------------------

// Runs argv[0] (found on PATH as `tool_path`) without a shell; its output goes where ours goes.
void run_step(const std::string& step, const std::string& tool_path, const std::vector<std::string>& argv) {
  std::cerr << "hmc flash: running: " << shell_line(argv) << "\n";
  std::cout.flush();
  std::cerr.flush();
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) fail(kExitIo, step + ": cannot start " + argv[0] + ": " + std::strerror(errno));
  if (pid == 0) {
    ::execv(tool_path.c_str(), args.data());
    const std::string msg = "hmc flash: error: cannot run " + tool_path + ": " + std::strerror(errno) + "\n";
    const ssize_t ignored = ::write(STDERR_FILENO, msg.data(), msg.size());
    static_cast<void>(ignored);
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) fail(kExitIo, step + ": lost " + argv[0] + ": " + std::strerror(errno));
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                            : "signal " + std::to_string(WTERMSIG(status));
  fail(kExitIo, step + " failed: " + argv[0] + " ended with " + how);
}

// The 1200-baud touch: open at 1200 baud, drop DTR, close. Firmware with a native USB serial
// port (ArduinoCore-samd) resets into the bootloader when it sees this.
void touch_1200(const std::string& port) {
  const int fd = ::open(port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd < 0)
    fail(kExitIo, "1200-baud touch: cannot open " + port + ": " + std::strerror(errno) +
                      " (the touch reaches firmware with a native USB serial port, which the hmc firmware does not "
                      "have: double-tap reset, then run again with --no-touch and the bootloader's port)");
  termios tio{};
  if (::tcgetattr(fd, &tio) == 0) {
    ::cfsetispeed(&tio, B1200);
    ::cfsetospeed(&tio, B1200);
    tio.c_cflag |= HUPCL;
    ::tcsetattr(fd, TCSANOW, &tio);
  }
  int dtr = TIOCM_DTR;
  ::ioctl(fd, TIOCMBIC, &dtr);
  ::close(fd);
}

// After the touch the port goes away while the chip resets, then the bootloader's port appears
// (usually under the same name). Waits for it to go (up to 2 s) and come back (up to 10 s).
void wait_for_bootloader(const std::string& port) {
  using namespace std::chrono_literals;
  std::error_code ec;
  for (auto end = std::chrono::steady_clock::now() + 2s; std::chrono::steady_clock::now() < end;) {
    if (!fs::exists(port, ec)) break;
    std::this_thread::sleep_for(50ms);
  }
  for (auto end = std::chrono::steady_clock::now() + 10s; std::chrono::steady_clock::now() < end;) {
    if (fs::exists(port, ec)) {
      std::this_thread::sleep_for(300ms);  // let udev finish with it
      return;
    }
    std::this_thread::sleep_for(100ms);
  }
  fail(kExitIo, "waiting for the bootloader: " + port +
                    " did not come back within 10 s (the touch only works while firmware with a native USB port "
                    "runs: double-tap reset instead, then use --no-touch with the bootloader's port)");
}

std::vector<std::string> uf2_drives() {
  std::vector<std::string> found;
  const char* user = std::getenv("USER");
  std::vector<fs::path> parents{"/mnt"};
  if (user != nullptr && *user != '\0') {
    parents.insert(parents.begin(), fs::path("/run/media") / user);
    parents.insert(parents.begin(), fs::path("/media") / user);
  }
  for (const auto& parent : parents) {
    std::error_code ec;
    for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
      std::error_code ec2;
      if (fs::is_regular_file(it->path() / "INFO_UF2.TXT", ec2)) found.push_back(it->path().string());
    }
  }
  return found;
}

void copy_to_drive(const std::string& file, const std::vector<unsigned char>& bytes, const std::string& target) {
  std::cerr << "hmc flash: copying " << file << " to " << target << "\n";
  const int fd = ::open(target.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) fail(kExitIo, "copy to the UF2 drive: cannot create " + target + ": " + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      fail(kExitIo, "copy to the UF2 drive: writing " + target + " failed after " + std::to_string(done) + " bytes: " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  // The bootloader may restart (and the drive vanish) as soon as the last block lands, so a
  // failing fsync/close after every byte was written is not an error.
  ::fsync(fd);
  ::close(fd);
}

// --- the command ----------------------------------------------------------------------------

std::uint32_t parse_offset(const std::string& text) {
  if (text.empty()) return kAppOffset;
  std::size_t used = 0;
  unsigned long v = 0;
  try {
    v = std::stoul(text, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text[0] == '-' || v >= kFlashSize || v % 256 != 0)
    fail(kExitUsage, "--offset " + text + ": expected a flash address on a 256-byte row, e.g. 0x2000 or 0x0");
  return static_cast<std::uint32_t>(v);
}

std::string tool_or_note(const std::string& tool, const std::string& package, bool dry_run) {
  if (auto path = find_in_path(tool)) return *path;
  const std::string msg = tool + " is not installed (not found on PATH; Debian package " + package +
                          ": sudo apt-get install " + package + ")";
  if (!dry_run) fail(kExitIo, msg);
  std::cerr << "hmc flash: note: " << msg << "\n";
  return tool;
}

int run_flash(const FlashOptions& o) {
  if (!o.offset_text.empty() && o.method != "openocd")
    fail(kExitUsage, "--offset is for --method openocd (bossac and UF2 always write behind the bootloader, at 0x2000)");
  const std::uint32_t offset = parse_offset(o.offset_text);
  const std::string file = o.file.empty() ? default_file(o.method, offset) : o.file;
  std::error_code ec;
  if (!fs::exists(file, ec)) fail(kExitIo, "cannot read '" + file + "': no such file");
  if (fs::is_directory(file, ec)) fail(kExitIo, "'" + file + "' is a directory, not an image");
  const std::vector<unsigned char> bytes = read_file(file);
  const std::string abs = fs::absolute(file, ec).lexically_normal().string();

  const std::optional<ImageInfo> info = image_info(bytes);
  const auto ask_line = [&o, &info] {
    if (o.ver_port.empty()) return;
    std::cout << "# ask VER on " << shell_quote(o.ver_port);
    if (info && info->firmware && info->protocol) {
      std::cout << ", expect firmware " << firmware_version_text(*info->firmware) << ", protocol " << *info->protocol;
    }
    std::cout << "\n";
  };

  if (o.method == "bossac") {
    check_raw_image(file, bytes, kAppOffset);
    announce_image(info);
    std::string port = o.port;
    if (port.empty()) {
      const char* env = std::getenv("HMC_PORT");
      if (env != nullptr) port = env;
    }
    if (port.empty())
      fail(kExitUsage, "bossac needs the board's native USB port: give --port (e.g. --port /dev/ttyACM0) or set HMC_PORT");
    const std::string tool = tool_or_note("bossac", "bossa-cli", o.dry_run);
    const std::vector<std::string> argv{"bossac", "-U", "-p", port, "--offset=0x2000", "-e", "-w", "-v", "-b", "-R", abs};
    if (o.dry_run) {
      if (!o.no_touch) {
        std::cout << "# 1200-baud touch: open " << shell_quote(port) << " at 1200 baud, drop DTR, close\n";
        std::cout << "# wait up to 10 s for the bootloader's port " << shell_quote(port) << "\n";
      }
      std::cout << shell_line(argv) << "\n";
      ask_line();
      return kExitOk;
    }
    if (!o.no_touch) {
      std::cerr << "hmc flash: 1200-baud touch on " << port << "\n";
      touch_1200(port);
      wait_for_bootloader(port);
    }
    run_step("writing with bossac", tool, argv);
    std::cerr << "hmc flash: done: " << abs << " written at 0x2000 and verified; the board restarts into it\n";
    return confirm_version(o.ver_port, o.ver_wait_s, info);
  }

  if (o.method == "openocd") {
    check_raw_image(file, bytes, offset);
    announce_image(info);
    const std::string tool = tool_or_note("openocd", "openocd", o.dry_run);
    std::vector<std::string> argv{"openocd", "-f", "interface/" + o.probe + ".cfg"};
    if (o.probe == "jlink") argv.insert(argv.end(), {"-c", "transport select swd"});  // J-Link defaults to JTAG
    argv.insert(argv.end(), {"-c", "set CHIPNAME at91samd21g18", "-f", "target/at91samdXX.cfg", "-c",
                             "program " + tcl_word(abs) + " verify reset " + offset_hex(offset) + "; shutdown"});
    if (o.dry_run) {
      std::cout << shell_line(argv) << "\n";
      ask_line();
      return kExitOk;
    }
    run_step("programming with openocd", tool, argv);
    std::cerr << "hmc flash: done: " << abs << " written at " << offset_hex(offset) << " and verified\n";
    return confirm_version(o.ver_port, o.ver_wait_s, info);
  }

  // uf2
  check_uf2_image(file, bytes);
  announce_image(info);
  const std::string name = fs::path(file).filename().string();
  std::string drive = o.drive;
  if (drive.empty()) {
    const auto drives = uf2_drives();
    if (drives.size() > 1) {
      std::string list;
      for (const auto& d : drives) list += " " + d;
      fail(kExitUsage, "several UF2 drives are mounted:" + list + ": choose one with --drive");
    }
    if (drives.empty()) {
      const std::string msg = "no UF2 drive found (no INFO_UF2.TXT under /media/$USER/*, /run/media/$USER/*, /mnt/*): "
                              "double-tap reset to show the drive, or give --drive";
      if (!o.dry_run) fail(kExitIo, msg);
      std::cerr << "hmc flash: note: " << msg << "\n";
      std::cout << shell_line({"cp", abs, "<UF2 drive>/" + name}) << "\n";
      ask_line();
      return kExitOk;
    }
    drive = drives.front();
  }
  drive = fs::absolute(drive, ec).lexically_normal().string();
  const std::string target = (fs::path(drive) / name).string();
  if (!fs::is_regular_file(fs::path(drive) / "INFO_UF2.TXT", ec)) {
    const std::string msg = "not a UF2 drive: no INFO_UF2.TXT in " + drive + " (double-tap reset to show the drive)";
    if (!o.dry_run) fail(kExitIo, msg);
    std::cerr << "hmc flash: note: " << msg << "\n";
  }
  if (o.dry_run) {
    std::cout << shell_line({"cp", abs, target}) << "\n";
    ask_line();
    return kExitOk;
  }
  copy_to_drive(abs, bytes, target);
  std::cerr << "hmc flash: done: the bootloader writes " << bytes.size() / kUf2Block
            << " blocks and restarts into the firmware; the drive disappears\n";
  return confirm_version(o.ver_port, o.ver_wait_s, info);
}

}  // namespace

void add_flash_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<FlashOptions>();
  CLI::App* flash = app.add_subcommand("flash", "Flash the firmware onto a SAMD21 board (bossac, OpenOCD or UF2 drive)");
  flash->add_option("file", options->file,
                    "Image: a raw .bin (bossac, openocd) or a .uf2 (uf2); default: this repository's "
                    "build/firmware/firmware/targets/samd21/hmc-firmware.bin or .uf2");
  flash->add_option("--method,-m", options->method, "bossac (native USB bootloader), openocd (SWD probe) or uf2 (drive)")
      ->check(CLI::IsMember({"bossac", "openocd", "uf2"}))
      ->capture_default_str();
  flash->add_option("--port,-p", options->port, "bossac: the board's native USB serial port (default: $HMC_PORT)");
  flash->add_flag("--no-touch", options->no_touch,
                  "bossac: skip the 1200-baud touch (the board is already in the bootloader, e.g. after a double-tap reset)");
  flash->add_option("--drive", options->drive, "uf2: the mounted UF2 drive (default: found by its INFO_UF2.TXT)");
  flash->add_option("--offset", options->offset_text,
                    "openocd: flash address to write at, 0x2000 (default, behind the bootloader) or 0x0 (hmc-firmware-nobl)");
  flash->add_option("--probe", options->probe, "openocd: the SWD probe, cmsis-dap or jlink")
      ->check(CLI::IsMember({"cmsis-dap", "jlink"}))
      ->capture_default_str();
  flash->add_option("--ver-port", options->ver_port,
                    "After writing, ask VER on this port (the board's command UART, e.g. /dev/ttyUSB0; or tcp:, sim://) "
                    "and check it against the image's versions");
  flash->add_option("--ver-wait", options->ver_wait_s, "Seconds to keep asking VER while the board restarts")
      ->check(positive_number())
      ->capture_default_str();
  flash->add_flag("--dry-run,-n", options->dry_run, "Print the commands and actions, one per line, and run nothing");
  flash->callback([options, &exit_code] {
    try {
      exit_code = run_flash(*options);
    } catch (const Failure& f) {
      std::cout.flush();
      std::cerr << "hmc flash: error: " << f.message << "\n";
      exit_code = f.code;
    }
  });
}

}  // namespace hmc::cli
