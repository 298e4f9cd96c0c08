#!/usr/bin/env bash
# Tests `hmc flash` without a board: dry-run output for each method, the refusals and their exit
# codes, real runs against fake bossac/openocd on PATH, and a real copy to a fake UF2 drive.
# Usage: flash_test.sh HMC_BINARY SOURCE_DIR
set -uo pipefail
hmc=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")  # absolute: the test works in a temp dir
src=$2
failures=0
checks=0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

# Test images: a raw image linked at 0x2000 (reset vector 0x2101), one linked at 0x0, an ELF
# header, and a one-block SAMD21 UF2 file.
python3 - <<'EOF'
import struct
open('fw.bin', 'wb').write(struct.pack('<II', 0x20007FF8, 0x2101) + bytes(504))
open('fw-nobl.bin', 'wb').write(struct.pack('<II', 0x20007FF8, 0x0101) + bytes(504))
open('fw.elf', 'wb').write(b'\x7fELF' + bytes(60))
head = struct.pack('<8I', 0x0A324655, 0x9E5D5157, 0x2000, 0x2000, 256, 0, 1, 0x68ED2B88)
block = head + bytes(476) + struct.pack('<I', 0x0AB16F30)
open('fw.uf2', 'wb').write(block)
open('other.uf2', 'wb').write(block[:28] + struct.pack('<I', 0xADA52840) + block[32:])
EOF

# run COMMAND...: runs it with a timeout; sets $out (stdout), $err (stderr) and $code.
run() {
  out=$(timeout 20 "$@" 2>"$tmp/stderr")
  code=$?
  err=$(cat "$tmp/stderr")
}

# expect NAME WANT_EXIT WANT_STDOUT ERR_PATTERN -- COMMAND...: exit code, exact stdout, and
# stderr matching the extended regex (empty: anything).
expect() {
  local name=$1 want_exit=$2 want_out=$3 pattern=$4
  shift 5
  run "$@"
  checks=$((checks + 1))
  if [[ $code -ne $want_exit || $out != "$want_out" ]] || { [[ -n $pattern ]] && ! grep -Eq -- "$pattern" <<<"$err"; }; then
    failures=$((failures + 1))
    printf 'FAIL %s: exit %s (want %s)\nstdout:\n%s\nwant stdout:\n%s\nstderr:\n%s\n' \
      "$name" "$code" "$want_exit" "$out" "$want_out" "$err"
  fi
}

# No real tools, no drives: a PATH holding only what the test needs.
mkdir -p nobin empty-drive drive fakebin
touch drive/INFO_UF2.TXT
export PATH="$tmp/nobin:/usr/bin:/bin"
unset HMC_PORT
have_real_tools=0
command -v bossac >/dev/null || command -v openocd >/dev/null && have_real_tools=1

# --- dry runs: the exact lines ---
expect dry-bossac 0 "# 1200-baud touch: open /dev/ttyACM0 at 1200 baud, drop DTR, close
# wait up to 10 s for the bootloader's port /dev/ttyACM0
bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/fw.bin" '' -- "$hmc" flash fw.bin --port /dev/ttyACM0 --dry-run
expect dry-bossac-env-no-touch 0 "bossac -U -p /dev/ttyACM1 --offset=0x2000 -e -w -v -b -R $tmp/fw.bin" '' -- \
  env HMC_PORT=/dev/ttyACM1 "$hmc" flash fw.bin --no-touch --dry-run
expect dry-openocd 0 "openocd -f interface/cmsis-dap.cfg -c 'set CHIPNAME at91samd21g18' -f target/at91samdXX.cfg -c 'program $tmp/fw.bin verify reset 0x2000; shutdown'" '' -- \
  "$hmc" flash fw.bin --method openocd --dry-run
expect dry-openocd-nobl-jlink 0 "openocd -f interface/jlink.cfg -c 'transport select swd' -c 'set CHIPNAME at91samd21g18' -f target/at91samdXX.cfg -c 'program $tmp/fw-nobl.bin verify reset 0x0; shutdown'" '' -- \
  "$hmc" flash fw-nobl.bin --method openocd --offset 0x0 --probe jlink --dry-run
expect dry-uf2 0 "cp $tmp/fw.uf2 $tmp/drive/fw.uf2" '' -- "$hmc" flash fw.uf2 --method uf2 --drive drive --dry-run
if [[ $have_real_tools -eq 0 ]]; then
  expect dry-note-bossac 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/fw.bin" \
    'note: bossac is not installed.*bossa-cli' -- "$hmc" flash fw.bin -p /dev/ttyACM0 --no-touch -n
  expect dry-note-openocd 0 "openocd -f interface/cmsis-dap.cfg -c 'set CHIPNAME at91samd21g18' -f target/at91samdXX.cfg -c 'program $tmp/fw.bin verify reset 0x2000; shutdown'" \
    'note: openocd is not installed.*Debian package openocd' -- "$hmc" flash fw.bin -m openocd -n
fi
# A path with a space: shell-quoted, and braced for OpenOCD's Tcl.
cp fw.bin 'my fw.bin'
expect dry-quoting 0 "openocd -f interface/cmsis-dap.cfg -c 'set CHIPNAME at91samd21g18' -f target/at91samdXX.cfg -c 'program {$tmp/my fw.bin} verify reset 0x2000; shutdown'" '' -- \
  "$hmc" flash 'my fw.bin' -m openocd -n

# --- refusals (they apply in dry runs too) ---
expect missing-file 3 '' "cannot read 'nothere.bin': no such file" -- "$hmc" flash nothere.bin -p /dev/ttyACM0 -n
expect elf-to-bossac 1 '' "'fw.elf' is an ELF file, not a raw image: use the .bin made from it \(fw.bin\)" -- \
  "$hmc" flash fw.elf -p /dev/ttyACM0 -n
expect elf-to-openocd 1 '' 'is an ELF file' -- "$hmc" flash fw.elf -m openocd -n
expect uf2-to-bossac 1 '' "'fw.uf2' is a UF2 file, not a raw image: use --method uf2 for it, or the .bin \(fw.bin\)" -- \
  "$hmc" flash fw.uf2 -p /dev/ttyACM0 -n
expect bin-to-uf2 1 '' "'fw.bin' is not a UF2 file .*use the .uf2 \(fw.uf2\)" -- "$hmc" flash fw.bin -m uf2 --drive drive -n
expect elf-to-uf2 1 '' 'is an ELF file, not UF2' -- "$hmc" flash fw.elf -m uf2 --drive drive -n
expect uf2-wrong-family 1 '' 'not for the SAMD21: its first block.s family id is 0xADA52840, not 0x68ED2B88' -- \
  "$hmc" flash other.uf2 -m uf2 --drive drive -n
expect nobl-at-0x2000 1 '' 'reset vector 0x00000100 is outside.*--offset 0x0' -- "$hmc" flash fw-nobl.bin -m openocd -n
expect app-at-0x0 1 '' 'does not look linked for 0x0' -- "$hmc" flash fw.bin -m openocd --offset 0 -n
expect no-port 2 '' 'give --port .* or set HMC_PORT' -- "$hmc" flash fw.bin -n
expect bad-method 2 '' '--method: foo not in' -- "$hmc" flash fw.bin --method foo -n
expect bad-probe 2 '' '--probe: stlink not in' -- "$hmc" flash fw.bin -m openocd --probe stlink -n
expect bad-offset 2 '' '--offset 0x2001: expected' -- "$hmc" flash fw.bin -m openocd --offset 0x2001 -n
expect offset-not-openocd 2 '' '--offset is for --method openocd' -- "$hmc" flash fw.bin -p /dev/ttyACM0 --offset 0x0 -n
expect empty-drive 3 '' "not a UF2 drive: no INFO_UF2.TXT in $tmp/empty-drive" -- "$hmc" flash fw.uf2 -m uf2 --drive empty-drive
if [[ $have_real_tools -eq 0 ]]; then
  expect missing-bossac 3 '' 'bossac is not installed.*Debian package bossa-cli' -- "$hmc" flash fw.bin -p /dev/ttyACM0
  expect missing-openocd 3 '' 'openocd is not installed.*Debian package openocd' -- "$hmc" flash fw.bin -m openocd
fi

# --- the default file: found from the executable's location ---
mkdir -p repo/firmware/targets/samd21 repo/bin
touch repo/CMakePresets.json
cp "$hmc" repo/bin/hmc
expect default-not-built 3 '' "firmware is not built: $tmp/repo/build/firmware/firmware/targets/samd21/hmc-firmware.bin does not exist \(run: cmake --preset firmware && cmake --build build/firmware" -- \
  repo/bin/hmc flash -p /dev/ttyACM0 -n
mkdir -p repo/build/firmware/firmware/targets/samd21
cp fw.bin repo/build/firmware/firmware/targets/samd21/hmc-firmware.bin
cp fw-nobl.bin repo/build/firmware/firmware/targets/samd21/hmc-firmware-nobl.bin
cp fw.uf2 repo/build/firmware/firmware/targets/samd21/hmc-firmware.uf2
expect default-bin 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/repo/build/firmware/firmware/targets/samd21/hmc-firmware.bin" '' -- \
  repo/bin/hmc flash -p /dev/ttyACM0 --no-touch -n
expect default-nobl 0 "openocd -f interface/cmsis-dap.cfg -c 'set CHIPNAME at91samd21g18' -f target/at91samdXX.cfg -c 'program $tmp/repo/build/firmware/firmware/targets/samd21/hmc-firmware-nobl.bin verify reset 0x0; shutdown'" '' -- \
  repo/bin/hmc flash -m openocd --offset 0x0 -n
expect default-uf2 0 "cp $tmp/repo/build/firmware/firmware/targets/samd21/hmc-firmware.uf2 $tmp/drive/hmc-firmware.uf2" '' -- \
  repo/bin/hmc flash -m uf2 --drive drive -n

# --- real runs: fake tools on PATH record their arguments; failures name the step ---
cat >fakebin/openocd <<'EOF'
#!/bin/sh
printf '%s\n' "$@" >"$FAKE_ARGS"
echo "fake openocd output"
exit "${FAKE_EXIT:-0}"
EOF
cp fakebin/openocd fakebin/bossac
chmod +x fakebin/openocd fakebin/bossac
export FAKE_ARGS=$tmp/args
expect run-openocd 0 'fake openocd output' 'done: .* written at 0x2000 and verified' -- env PATH="$tmp/fakebin:$PATH" "$hmc" flash fw.bin -m openocd
checks=$((checks + 1))
want_args="-f
interface/cmsis-dap.cfg
-c
set CHIPNAME at91samd21g18
-f
target/at91samdXX.cfg
-c
program $tmp/fw.bin verify reset 0x2000; shutdown"
[[ $(cat args) == "$want_args" ]] || { failures=$((failures + 1)); printf 'FAIL run-openocd-args:\n%s\n' "$(cat args)"; }
expect run-openocd-fails 3 'fake openocd output' 'error: programming with openocd failed: openocd ended with exit status 1' -- \
  env FAKE_EXIT=1 PATH="$tmp/fakebin:$PATH" "$hmc" flash fw.bin -m openocd
expect run-bossac-no-touch 0 'fake openocd output' 'written at 0x2000' -- env PATH="$tmp/fakebin:$PATH" "$hmc" flash fw.bin -p /dev/ttyACM0 --no-touch
checks=$((checks + 1))
[[ $(tr '\n' ' ' <args) == "-U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/fw.bin " ]] ||
  { failures=$((failures + 1)); printf 'FAIL run-bossac-args:\n%s\n' "$(cat args)"; }
expect run-bossac-touch-no-port 3 '' '1200-baud touch: cannot open /nonexistent/ttyACM9' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash fw.bin -p /nonexistent/ttyACM9

# --- the board variant named from the image, its guessed pins, the board's VER after writing ---
python3 - <<'PYEOF'
import struct
def image(info):
    text = info.encode() + b'\0'
    return struct.pack('<II', 0x20007FF8, 0x2101) + bytes(0xB0 - 8) + text + bytes(512 - 0xB0 - len(text))
seed = 'hmc-board:seed;protocol:7;firmware:100;guessed:PA05,PA06;'
open('board.bin', 'wb').write(image(seed))
open('board-proto2.bin', 'wb').write(image('hmc-board:bench;protocol:2;firmware:100;guessed:PA05;'))
# A UF2 file whose info text straddles its two blocks' payloads.
payload = bytes(250) + seed.encode() + b'\0'
payload += bytes(512 - len(payload))
blocks = b''
for n in range(2):
    head = struct.pack('<8I', 0x0A324655, 0x9E5D5157, 0x2000, 0x2000 + 256 * n, 256, n, 2, 0x68ED2B88)
    blocks += head + payload[256 * n:256 * (n + 1)] + bytes(220) + struct.pack('<I', 0x0AB16F30)
open('board.uf2', 'wb').write(blocks)
PYEOF
export HMC_SIM_STATE=$tmp/sim-state
expect variant-named 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/board.bin" \
  "image for board variant 'seed', firmware 0\.1\.0, protocol 7$" -- "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch -n
expect variant-guessed-pins 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/board.bin" \
  "warning: 2 pins of variant 'seed' are guessed, not verified on a real board: PA05, PA06\. Check them" -- \
  "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch -n
expect variant-unknown 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/fw.bin" \
  'note: the image names no board variant' -- "$hmc" flash fw.bin -p /dev/ttyACM0 --no-touch -n
expect variant-uf2-across-blocks 0 "cp $tmp/board.uf2 $tmp/drive/board.uf2" "image for board variant 'seed'" -- \
  "$hmc" flash board.uf2 -m uf2 --drive drive -n
expect dry-ver-port 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $tmp/board.bin
# ask VER on 'sim://?fast', expect firmware 0.1.0, protocol 7" '' -- \
  "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch --ver-port 'sim://?fast' -n
expect ver-confirmed 0 'fake openocd output' 'sim://\?fast answers VER: firmware 0\.1\.0, protocol 7$' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch --ver-port 'sim://?fast'
expect ver-confirmed-said 0 'fake openocd output' '^hmc flash: confirmed: the board runs the new firmware$' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch --ver-port 'sim://?fast'
expect ver-not-asked 0 'fake openocd output' 'not confirmed: give --ver-port' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash board.bin -p /dev/ttyACM0 --no-touch
expect ver-mismatch 1 'fake openocd output' 'error: that is not the image just written \(firmware 0\.1\.0, protocol 2\)' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash board-proto2.bin -p /dev/ttyACM0 --no-touch --ver-port 'sim://?fast'
expect ver-no-board 4 'fake openocd output' 'could not confirm the new firmware on /nonexistent/ttyUSB9 within 0\.5 s' -- \
  env PATH="$tmp/fakebin:$PATH" "$hmc" flash board.bin -m openocd --ver-port /nonexistent/ttyUSB9 --ver-wait 0.5
# The real image, when the firmware is built: its variant is the build's (default seed).
real=$src/build/firmware/firmware/targets/samd21/hmc-firmware.bin
if [[ -f $real ]]; then
  expect real-image-variant 0 "bossac -U -p /dev/ttyACM0 --offset=0x2000 -e -w -v -b -R $real" \
    "image for board variant '(seed|bench)', firmware [0-9.]+, protocol [0-9]+" -- "$hmc" flash "$real" -p /dev/ttyACM0 --no-touch -n
fi

# --- a real UF2 copy to a fake drive ---
expect uf2-copy 0 '' 'copying .* to .*drive/fw.uf2' -- "$hmc" flash fw.uf2 -m uf2 --drive drive
checks=$((checks + 1))
cmp -s fw.uf2 drive/fw.uf2 || { failures=$((failures + 1)); echo "FAIL uf2-copy: drive/fw.uf2 missing or different"; }

echo "$checks checks, $failures failures"
[[ $failures -eq 0 ]]
