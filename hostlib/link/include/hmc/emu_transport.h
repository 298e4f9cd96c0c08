// emu://: the real firmware image on the SAMD21 emulator, hmc-emu, started for the command as a
// child process on a pseudo-terminal (docs/emu.md, "emu:// in every command"). libhmc does not
// link the emulator: it runs the hmc-emu program.
//
//   emu://[IMAGE][?OPTION&...]
//     IMAGE          the image to run: an ELF (hmc-firmware.elf), or a raw .bin taken as the
//                    application at 0x2000 (hmc-firmware.bin); absolute (emu:///path/x.elf) or
//                    relative to the current directory; default: $HMC_EMU_FIRMWARE, else the
//                    firmware preset's ELF in the build tree above this program, else the
//                    installed one (<bindir>/../share/hmc/firmware/hmc-firmware.bin, the
//                    hmc-firmware package)
//     fast           virtual time unthrottled (hmc-emu --fast)
//     axis=M:LOW:HIGH:START   motor 1 or 2's switch positions and start (repeatable; hmc-emu --axis)
//     control=HOST:PORT       hmc-emu's control channel (press, release, estop, fault, status)
//     nocrystal      no 32.768 kHz crystal (hmc-emu --no-crystal)
//
// The program is $HMC_EMU, else hmc-emu beside this program, else in the build tree beside it
// (build/PRESET/emu/hmc-emu for build/PRESET/cli/hmc), else on PATH.
//
// Every open boots a new board: the port's first bytes are exchanged after the image's power-up
// self-test, and what the board said before (its boot event, the self-test's switch events) is
// dropped. The board lives as long as the port is open: closing it ends hmc-emu, and hmc-emu
// dies with this process (PR_SET_PDEATHSIG, and the pseudo-terminal's hang-up).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/result.h"
#include "hmc/transport.h"

namespace hmc {

struct EmuPortOptions {
  std::string image;               // empty: the default image
  bool fast = false;
  bool no_crystal = false;
  std::vector<std::string> axes;   // M:LOW:HIGH:START, checked by hmc-emu
  std::string control;             // HOST:PORT, checked by hmc-emu
  std::string trace;               // FILE for hmc-emu --trace (relative to the current directory)
};

// Splits the URL; an unknown option or a value where none belongs is an error naming it.
Result<EmuPortOptions> parse_emu_url(std::string_view url);

// Starts hmc-emu on `url`'s image and waits (at most a minute) until the booted board answers
// VER. Fails, saying what to do, when hmc-emu or the image cannot be found, or when hmc-emu ends
// before its board answers (its own message is on standard error above).
Result<std::unique_ptr<Transport>> open_emu_port(std::string_view url, const PortOptions& options);

}  // namespace hmc
