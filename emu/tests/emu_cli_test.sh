#!/usr/bin/env bash
# hmc against the real firmware image on the emulated board, over a pseudo-terminal, as a user
# would run it against a board: status reads the board's state and why it last reset, and a
# ramped move is waited for and ends where it was sent (issue 17's "done when", first line).
# Usage: emu_cli_test.sh HMC_EMU HMC IMAGE_DIR
# Without the image the test is skipped (exit 77), unless CI is set: then it fails.
set -uo pipefail
emu=$1
hmc=$2
image=$3/hmc-firmware.elf
work=$(mktemp -d)
emu_pid=
trap '[[ -n $emu_pid ]] && kill "$emu_pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
failures=0

if [[ ! -f $image ]]; then
  if [[ ${CI:-} == true ]]; then
    echo "FAIL: no firmware image $image (build the firmware preset first)"
    exit 1
  fi
  echo "SKIP: no firmware image $image (cmake --preset firmware && cmake --build --preset firmware)"
  exit 77
fi

expect() {  # NAME WANT_CODE REGEX -- COMMAND...
  local name=$1 want=$2 regex=$3
  shift 4
  local out code
  out=$("$@" 2>&1)
  code=$?
  if [[ $code != "$want" ]] || ! grep -Eq -- "$regex" <<<"$out"; then
    failures=$((failures + 1))
    printf 'FAIL %s: exit %s (want %s), no match for %s in:\n%s\n' "$name" "$code" "$want" "$regex" "$out"
  fi
}

# Real time (the board's UART at its baud rate); the emulator prints the pty's path.
"$emu" "$image" --pty >"$work/emu.out" 2>"$work/emu.err" &
emu_pid=$!
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

if ! kill -0 "$emu_pid" 2>/dev/null; then
  failures=$((failures + 1))
  echo "FAIL: hmc-emu stopped: $(cat "$work/emu.err")"
fi
[[ $failures == 0 ]] && echo "emu_cli_test: all checks passed" || echo "emu_cli_test: $failures failed"
[[ $failures == 0 ]]
