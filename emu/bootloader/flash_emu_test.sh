#!/usr/bin/env bash
# Flashing end to end against the emulated bootloader (hmc-emu-bootloader): Debian's real bossac
# and `hmc flash` over the pseudo-terminal that stands for the native USB port, the UF2 method
# into the directory that stands for the bootloader's drive; each run ends with the flash
# compared with the image. Usage:
#   flash_emu_test.sh HMC_EMU_BOOTLOADER HMC HMC_UF2 FIRMWARE_DIR
# The firmware image is built by the firmware preset; without it the test is skipped (exit 77),
# unless HMC_REQUIRE_FIRMWARE=1 (scripts/test), which makes a missing image a failure.
set -uo pipefail
emu=$1 hmc=$2 uf2tool=$3 fwdir=$4
image=$fwdir/hmc-firmware.bin
uf2=$fwdir/hmc-firmware.uf2
if [[ ! -f $image || ! -f $uf2 ]]; then
  echo "no firmware image in $fwdir (cmake --preset firmware && cmake --build --preset firmware)"
  [[ ${HMC_REQUIRE_FIRMWARE:-0} == 1 ]] && exit 1
  exit 77
fi
command -v bossac >/dev/null || { echo "bossac is not installed (Debian package bossa-cli)"; exit 1; }
tmp=$(mktemp -d)
emu_pid=
cleanup() {
  [[ -n $emu_pid ]] && kill "$emu_pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
failures=0
fail() {
  failures=$((failures + 1))
  echo "FAIL $*"
}

# The flash before each run: a "bootloader" pattern in 0x0-0x1FFF (which nothing may change)
# and an old image's bytes above it (which the erase must clear).
python3 - "$tmp/before.bin" <<'EOF'
import sys, random
random.seed(17)
open(sys.argv[1], 'wb').write(bytes([0xB0, 0x07]) * 4096 + bytes(random.randrange(256) for _ in range(256 * 1024 - 8192)))
EOF

# start_emu NAME ARGS...: starts the emulated bootloader on the old flash, waits for its ports.
start_emu() {
  local name=$1
  shift
  "$emu" --flash "$tmp/before.bin" --flash-out "$tmp/$name.flash" "$@" 2>"$tmp/$name.emu.log" &
  emu_pid=$!
  for _ in $(seq 50); do
    grep -q -e 'usb pty' -e 'uf2 drive' "$tmp/$name.emu.log" && return 0
    sleep 0.05
  done
  fail "$name: the emulated bootloader did not start: $(cat "$tmp/$name.emu.log")"
}

# wait_emu NAME: the bootloader must end by itself (reset into the application) within 10 s.
wait_emu() {
  local name=$1
  for _ in $(seq 100); do
    kill -0 "$emu_pid" 2>/dev/null || break
    sleep 0.1
  done
  if kill -0 "$emu_pid" 2>/dev/null; then
    fail "$name: the bootloader did not reset"
    kill "$emu_pid"
  fi
  wait "$emu_pid"
  emu_pid=
  grep -q 'the bootloader would start the application' "$tmp/$name.emu.log" ||
    fail "$name: no reset in the emulator's log: $(cat "$tmp/$name.emu.log")"
}

# check_flash NAME PAD: 0x0-0x1FFF as before, the image at 0x2000, then PAD (bossac fills the
# last page with zeros, the UF2 file's last block with 0xFF), then erased flash to the end (bossac
# -e erases from 0x2000 to the end; UF2 rewrites only its own rows, the rest is kept).
check_flash() {
  python3 - "$tmp/before.bin" "$tmp/$1.flash" "$image" "$2" <<'EOF' || fail "$1: flash contents"
import sys
before, after, image = (open(p, 'rb').read() for p in sys.argv[1:4])
pad, grain = int(sys.argv[4], 0), 64 if sys.argv[4] == '0x00' else 256
end = 0x2000 + len(image)
padded = (end + grain - 1) // grain * grain
problems = []
if len(after) != 256 * 1024: problems.append('flash is %d bytes' % len(after))
if after[:0x2000] != before[:0x2000]: problems.append('the boot section changed')
if after[0x2000:end] != image:
    first = next(i for i in range(len(image)) if after[0x2000 + i] != image[i])
    problems.append('image differs first at 0x%X' % (0x2000 + first))
if after[end:padded] != bytes([pad]) * (padded - end): problems.append('padding after the image')
rest = b'\xff' * (len(after) - padded) if pad == 0 else before[padded:]
if after[padded:] != rest: problems.append('flash after the image: not as expected')
if problems: print('; '.join(problems)); sys.exit(1)
EOF
}

# --- 1. bossac itself, as hmc flash runs it ---
start_emu bossac --usb-pty="$tmp/usb"
timeout 60 bossac -U -p "$tmp/usb" --offset=0x2000 -e -w -v -b -R "$image" >"$tmp/bossac.out" 2>&1 ||
  fail "bossac: exit $?: $(cat "$tmp/bossac.out")"
grep -q 'Verify successful' "$tmp/bossac.out" || fail "bossac did not verify: $(cat "$tmp/bossac.out")"
wait_emu bossac
check_flash bossac 0x00

# --- 2. hmc flash --method bossac --no-touch ---
start_emu hmc-bossac --usb-pty="$tmp/usb"
timeout 60 "$hmc" flash "$image" --method bossac --no-touch --port "$tmp/usb" >"$tmp/hmc.out" 2>&1 ||
  fail "hmc flash --method bossac: exit $?: $(cat "$tmp/hmc.out")"
grep -q 'done: .* written at 0x2000 and verified' "$tmp/hmc.out" || fail "hmc flash said: $(cat "$tmp/hmc.out")"
grep -q "image for board variant '[a-z]*', firmware [0-9.]*, protocol [0-9]*" "$tmp/hmc.out" ||
  fail "hmc flash did not name the image's board variant: $(cat "$tmp/hmc.out")"
wait_emu hmc-bossac
check_flash hmc-bossac 0x00

# --- 3. the 1200-baud touch: a port that leaves and comes back as the bootloader's ---
start_emu touch --usb-pty="$tmp/usb" --touch-to-enter
timeout 60 "$hmc" flash "$image" --method bossac --port "$tmp/usb" >"$tmp/touch.out" 2>&1 ||
  fail "hmc flash with the touch: exit $?: $(cat "$tmp/touch.out")"
grep -q '1200-baud touch seen: the USB port leaves' "$tmp/touch.emu.log" || fail "touch: not seen by the emulator"
wait_emu touch
check_flash touch 0x00

# --- 4. the boot section is protected (BOOTPROT): bossac cannot write at 0x0 ---
start_emu bootprot --usb-pty="$tmp/usb"
if timeout 60 bossac -U -p "$tmp/usb" --offset=0x0 -e -w -v "$image" >"$tmp/bootprot.out" 2>&1; then
  fail "bootprot: bossac wrote over the boot section: $(cat "$tmp/bootprot.out")"
fi
grep -q 'Verify failed' "$tmp/bootprot.out" || fail "bootprot: bossac said: $(cat "$tmp/bootprot.out")"
grep -q 'LOCKE' "$tmp/bootprot.emu.log" || fail "bootprot: no LOCKE in the emulator's log"
kill "$emu_pid"
wait "$emu_pid"
emu_pid=
cmp -s -n 8192 "$tmp/before.bin" "$tmp/bootprot.flash" || fail "bootprot: the boot section changed"

# --- 5. UF2: the drive as the bootloader presents it, then hmc flash --method uf2 ---
start_emu uf2 --uf2-drive "$tmp/drive"
[[ -f $tmp/drive/INFO_UF2.TXT ]] || fail "uf2: no INFO_UF2.TXT"
"$uf2tool" check "$tmp/drive/CURRENT.UF2" "$tmp/before.bin" --base 0 || fail "uf2: CURRENT.UF2 is not the flash"
timeout 60 "$hmc" flash "$uf2" --method uf2 --drive "$tmp/drive" >"$tmp/uf2.out" 2>&1 ||
  fail "hmc flash --method uf2: exit $?: $(cat "$tmp/uf2.out")"
wait_emu uf2
grep -q "hmc-firmware.uf2: $(($(stat -c %s "$uf2") / 512)) of .* blocks written" "$tmp/uf2.emu.log" ||
  fail "uf2: $(cat "$tmp/uf2.emu.log")"
check_flash uf2 0xFF

if [[ $failures -ne 0 ]]; then
  echo "$failures failure(s)"
  exit 1
fi
echo "flash_emu_test: bossac, hmc flash (no touch, touch), BOOTPROT and UF2 all passed"
