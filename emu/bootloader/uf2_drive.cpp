// The UF2 drive as a directory (uf2_drive.h).
#include "uf2_drive.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "nvmctrl.h"
#include "uf2.h"

namespace hmc::emu {
namespace {

namespace fs = std::filesystem;

uint32_t le32(const std::vector<uint8_t>& b, size_t at) {
  return static_cast<uint32_t>(b[at]) | static_cast<uint32_t>(b[at + 1]) << 8 |
         static_cast<uint32_t>(b[at + 2]) << 16 | static_cast<uint32_t>(b[at + 3]) << 24;
}

std::string hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

bool write_file(const fs::path& path, const std::vector<uint8_t>& bytes, std::string& error) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (out) return true;
  error = "cannot write " + path.string();
  return false;
}

bool is_uf2_name(const fs::path& path) {
  std::string ext = path.extension().string();
  for (auto& c : ext) c = static_cast<char>(c >= 'a' && c <= 'z' ? c - 32 : c);
  return ext == ".UF2" && path.filename() != "CURRENT.UF2";
}

}  // namespace

Uf2Drive::Uf2Drive(std::string directory, TargetBus& bus, std::function<void(const std::string&)> log)
    : directory_(std::move(directory)), flash_(bus), log_(std::move(log)) {}

bool Uf2Drive::present(const std::vector<uint8_t>& flash, std::string& error) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec) {
    error = "cannot create the UF2 drive " + directory_ + ": " + ec.message();
    return false;
  }
  const std::string info =
      "UF2 Bootloader hmc-emu\r\nModel: hmc-emu SAMD21G18A\r\nBoard-ID: SAMD21G18A-hmc-emu\r\n";
  uf2::Options whole_flash;
  whole_flash.base = 0;
  return write_file(fs::path(directory_) / "INFO_UF2.TXT", std::vector<uint8_t>(info.begin(), info.end()), error) &&
         write_file(fs::path(directory_) / "CURRENT.UF2", uf2::from_bin(flash, whole_flash), error);
}

size_t Uf2Drive::flash_file(const std::vector<uint8_t>& file, BootFlash& flash, std::string& error,
                            const std::function<void(const std::string&)>& log) {
  size_t written = 0;
  for (size_t at = 0; at + uf2::kBlockSize <= file.size(); at += uf2::kBlockSize) {
    const size_t n = at / uf2::kBlockSize;
    const uint32_t flags = le32(file, at + 8);
    const uint32_t address = le32(file, at + 12);
    const uint32_t size = le32(file, at + 16);
    std::string skip;
    if (le32(file, at) != uf2::kMagicStart0 || le32(file, at + 4) != uf2::kMagicStart1 ||
        le32(file, at + uf2::kBlockSize - 4) != uf2::kMagicEnd)
      skip = "not a UF2 block (magics)";
    else if ((flags & 0x1) != 0)
      skip = "flag 'not main flash'";
    else if ((flags & uf2::kFlagFamilyIdPresent) != 0 && le32(file, at + 28) != uf2::kFamilySamd21)
      skip = "family " + hex(le32(file, at + 28)) + ", not the SAMD21's";
    else if (size != uf2::kPayloadSize || address % Nvmctrl::kRowSize != 0)
      skip = "payload of " + std::to_string(size) + " bytes at " + hex(address) + " (256 at a row boundary expected)";
    else if (address < kAppStart || address >= Nvmctrl::kFlashSize)
      skip = "address " + hex(address) + " outside the application flash 0x00002000-0x0003FFFF";
    if (!skip.empty()) {
      if (log) log("uf2 drive: block " + std::to_string(n) + " skipped: " + skip);
      continue;
    }
    if (!flash.erase_row(address, error)) return written;
    for (uint32_t page = 0; page < Nvmctrl::kPagesPerRow; ++page) {
      uint32_t words[Nvmctrl::kPageSize / 4];
      for (uint32_t i = 0; i < Nvmctrl::kPageSize / 4; ++i)
        words[i] = le32(file, at + uf2::kDataOffset + page * Nvmctrl::kPageSize + 4 * i);
      if (!flash.write_page(address + page * Nvmctrl::kPageSize, words, error)) return written;
    }
    ++written;
  }
  return written;
}

bool Uf2Drive::poll() {
  std::error_code ec;
  for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file() || !is_uf2_name(it->path())) continue;
    std::ifstream in(it->path(), std::ios::binary);
    std::vector<uint8_t> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // Complete when it holds as many whole blocks as its first block announces.
    if (file.size() < uf2::kBlockSize || file.size() % uf2::kBlockSize != 0) continue;
    const uint32_t announced = le32(file, 24);
    if (file.size() / uf2::kBlockSize < announced) continue;
    std::string error;
    const size_t written = flash_file(file, flash_, error, log_);
    fs::remove(it->path(), ec);
    if (!error.empty()) {
      if (log_) log_("uf2 drive: " + it->path().filename().string() + ": " + error);
      return false;
    }
    if (log_)
      log_("uf2 drive: " + it->path().filename().string() + ": " + std::to_string(written) + " of " +
           std::to_string(file.size() / uf2::kBlockSize) + " blocks written");
    return written > 0;
  }
  return false;
}

}  // namespace hmc::emu
