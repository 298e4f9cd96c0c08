#!/usr/bin/env bash
# Runs the real hmc-emu on the real firmware images: each boots on both clock paths (crystal or
# not) and both start states (behind the bootloader at 0x2000, or alone at 0x0), sends only its
# boot event (no emergency or limit event with nothing pressed), answers VER, and breaks no
# chip rule (the IOBUS sampling rule of issue 17 defect 1; the DFLL48M start-up order of defect
# 2 shows as a hang caught by --max-time). Bad input gives a clear error and its exit code.
# --stats --count-calls counts the main loop's rounds.
# Usage: emu_boot_test.sh HMC_EMU IMAGE_DIR
# The images come from the firmware preset. Without them the test is skipped (exit 77), unless
# CI is set: then their absence is a failure.
set -uo pipefail
emu=$(realpath "$1")
images=$(realpath -m "$2")
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$images/hmc-firmware.elf" "$images/hmc-firmware-nobl.elf"

ver='STX#1#VER#0#ETX'
boot_out="STX#3#EVB#7#100#107#ETX
STX#6#EVR#1#0#0#0#0#1#ETX
STX#10#VER#7#100#0#128#150000#322#3#0#150000#16#ETX"
for image in hmc-firmware hmc-firmware-nobl; do
  for clock in "" --no-crystal; do
    name="$image${clock:+ $clock}"
    out=$(printf '%s\n' "$ver" | timeout 60 "$emu" "$images/$image.elf" --fast --max-time 5 $clock 2>"$work/err")
    code=$?
    check "$name: exit code" 0 "$code"
    check "$name: boot event and VER, nothing else" "$boot_out" "$out"
    check "$name: no complaint" "" "$(cat "$work/err")"
  done
done

# Bad input: a missing file, a file that is not ELF, a host (64-bit) ELF, an image linked
# for another address, a vector table that points outside flash.
"$emu" "$work/missing.elf" 2>"$work/err" </dev/null
check "missing image: exit code" 3 $?
check_match "missing image: message" "cannot read '.*missing.elf'" "$(cat "$work/err")"

printf 'not an image\n' >"$work/text.elf"
"$emu" "$work/text.elf" 2>"$work/err" </dev/null
check "text file: exit code" 4 $?
check_match "text file: message" "is not a firmware image: no ELF header" "$(cat "$work/err")"

"$emu" "$emu" 2>"$work/err" </dev/null
check "host ELF: exit code" 4 $?
check_match "host ELF: message" "is not a firmware image: not a 32-bit little-endian ELF" "$(cat "$work/err")"

# Copies of the real image, rewritten: every load address moved up 0x1000 (linked at 0x3000),
# and the reset vector pointing past the end of flash.
python3 - "$images" "$work" <<'PY'
import struct, sys
images, work = sys.argv[1], sys.argv[2]
elf = bytearray(open(images + "/hmc-firmware.elf", "rb").read())
phoff, = struct.unpack_from("<I", elf, 28)
phentsize, phnum = struct.unpack_from("<HH", elf, 42)
for i in range(phnum):
    at = phoff + i * phentsize
    if struct.unpack_from("<I", elf, at)[0] == 1:  # PT_LOAD: move p_paddr
        struct.pack_into("<I", elf, at + 12, struct.unpack_from("<I", elf, at + 12)[0] + 0x1000)
open(work + "/moved.elf", "wb").write(elf)
elf = bytearray(open(images + "/hmc-firmware-nobl.elf", "rb").read())
for i in range(phnum):
    at = phoff + i * phentsize
    if struct.unpack_from("<I", elf, at)[0] == 1 and struct.unpack_from("<I", elf, at + 12)[0] == 0:
        struct.pack_into("<I", elf, struct.unpack_from("<I", elf, at + 4)[0] + 4, 0x000FFFFF)
open(work + "/badvector.elf", "wb").write(elf)
PY
"$emu" "$work/moved.elf" 2>"$work/err" </dev/null
check "image at 0x3000: exit code" 4 $?
check_match "image at 0x3000: message" "is linked at 0x3000" "$(cat "$work/err")"
"$emu" "$work/badvector.elf" 2>"$work/err" </dev/null
check "reset vector outside flash: exit code" 4 $?
check_match "reset vector outside flash: message" "reset handler 0x000FFFFF, not a Thumb address in the image's flash" "$(cat "$work/err")"

# A hang: --max-time stops the run and names the function the PC is in.
timeout 60 "$emu" "$images/hmc-firmware.elf" --fast --max-time 0.05 >/dev/null 2>"$work/err" < <(sleep 30)
check "max time: exit code" 6 $?
check_match "max time: message" "--max-time reached at 0.050000 s of virtual time; PC in [a-z_:]" "$(cat "$work/err")"
# The firmware preset compiles with -g: the message names the source line too; an image without
# DWARF (stripped here) gets the function's name alone.
check_match "max time: source line" "PC in [a-zA-Z_:]+.*\(0x[0-9A-F]{8}, /[^ ]+\.(cpp|h):[0-9]+\)$" "$(cat "$work/err")"
arm-none-eabi-objcopy --strip-debug "$images/hmc-firmware.elf" "$work/stripped.elf"
timeout 60 "$emu" "$work/stripped.elf" --fast --max-time 0.05 >/dev/null 2>"$work/err" < <(sleep 30)
check "no DWARF: exit code" 6 $?
check_match "no DWARF: the function alone" "PC in [a-zA-Z_:]+.*\(0x[0-9A-F]{8}\)$" "$(cat "$work/err")"

# --count-calls: the main loop's rounds (Controller::poll) and its cycles per round; an idle
# board spends every cycle of the window in thread mode. A name the image lacks is a usage error.
timeout 60 "$emu" "$images/hmc-firmware.elf" --fast --stats --count-calls hmc::fw::Controller::poll \
  --measure-from 0.02 --max-time 0.05 >/dev/null 2>"$work/err" < <(sleep 30)
check "count calls: exit code" 6 $?
check_match "count calls: thread mode" "thread mode \(the main loop\): [0-9]+ cycles" "$(cat "$work/err")"
check_match "count calls: calls" "hmc::fw::Controller::poll: [1-9][0-9]+ calls, [0-9.]+ thread-mode cycles per call" \
  "$(cat "$work/err")"
"$emu" "$images/hmc-firmware.elf" --stats --count-calls no_such_function 2>"$work/err" </dev/null
check "count calls, unknown name: exit code" 2 $?
check_match "count calls, unknown name: message" "--count-calls 'no_such_function': no function of that name" \
  "$(cat "$work/err")"

echo "$checks checks, $failures failures"
[[ $failures -eq 0 ]]
