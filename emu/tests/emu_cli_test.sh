#!/usr/bin/env bash
# hmc against the real firmware image on the emulated board, over a pseudo-terminal, as a user
# would run it against a board: status reads the board's state and why it last reset, and a
# ramped move is waited for and ends where it was sent (issue 17's "done when", first line).
# Usage: emu_cli_test.sh HMC_EMU HMC IMAGE_DIR
# Without the image the test is skipped (exit 77), unless CI is set: then it fails.
set -uo pipefail
emu=$(realpath "$1")
hmc=$(realpath "$2")
image=$(realpath -m "$3")/hmc-firmware.elf
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$image"

# Real time (the board's UART at its baud rate); the emulator prints the pty's path.
"$emu" "$image" --pty >"$work/emu.out" 2>"$work/emu.err" &
emu_pid=$!
pids+=("$emu_pid")
pty=
for _ in $(seq 100); do
  pty=$(grep -o '/dev/pts/[0-9]*' "$work/emu.out" "$work/emu.err" | head -1 | cut -d: -f2)
  [[ -n $pty ]] && break
  sleep 0.05
done
if [[ -z $pty ]]; then
  echo "FAIL: hmc-emu printed no pseudo-terminal: $(cat "$work/emu.out" "$work/emu.err")"
  exit 1
fi
# The power-up self-test (each stepper half a turn out and back) ends before the checks begin:
# the emulator may run slower than real time on a loaded machine, so wait for it by asking. The
# move below is relative to where status then finds motor 1.
for _ in $(seq 60); do
  out=$("$hmc" --port "$pty" --timeout 5000 status 2>&1) && ! grep -q 'self_test' <<<"$out" && break
  sleep 0.5
done
start=$(awk '$1 == "1" && $2 == "idle" { print $3 }' <<<"$out")
if [[ -z $start ]]; then
  echo "FAIL: status shows no idle motor 1: $out"
  exit 1
fi
end=$((start + 3200))

# The emulator may run slower than real time on a loaded machine: generous reply timeouts.
expect status 0 '^last reset: power-on$' -- "$hmc" --port "$pty" --timeout 5000 status
expect status-protocol 0 'firmware [0-9.]+, protocol [0-9]+' -- "$hmc" --port "$pty" --timeout 5000 status
expect move-wait 0 "^motor 1: done, at $end steps of 1/16" -- \
  "$hmc" --port "$pty" --timeout 5000 move 1 3200 --accel 8000 --wait
expect status-after 0 "^1 +idle +$end +$end " -- "$hmc" --port "$pty" --timeout 5000 status

kill -0 "$emu_pid" 2>/dev/null || fail "hmc-emu stopped: $(cat "$work/emu.err")"
finish emu_cli_test
