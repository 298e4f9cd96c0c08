#!/usr/bin/env bash
# The real image's step interrupt in hmc-emu: one motor at 100 us (10 000 steps/s) makes one
# interrupt per step, each within its period. Fails if an interrupt held back by PRIMASK waits for
# the next peripheral event instead of the CPSIE (the step engine then catches up with a burst
# of steps in one interrupt: before the fix, 4 940 interrupts for 9 001 steps). The STEP pulses
# are the DMA's (firmware/targets/samd21/step_pulses.h): each high 2.0 us (kStepHighTicks; the
# DRV8711 wants >= 1.9 us high and low) and rising exactly 100 us after the one before. Fails if
# the DMA's clear did not come (a pulse too long or too short) or a rise came off its compare
# (the CPU-made pulses before measured high 3.0-3.8 us and periods 98.4-101.5 us). Then one motor
# ramping toward 25 us: every pulse 2.0 us high there too (a pulse end the DMAC's beat set late,
# once the counter had passed it, left STEP high until the next step's end: that step was lost).
# Usage: step_timing_test.sh HMC_EMU IMAGE_DIR
# Without the images the test is skipped (77), unless CI=true.
set -uo pipefail
emu=$(realpath "$1")
image=$(realpath -m "$2")/hmc-firmware.elf
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$image"
# run_stats LINES MAX_TIME: hmc-emu's --stats from 0.3 s to MAX_TIME with LINES on its standard
# input, which stays open until --max-time ends the run (at its end hmc-emu would stop early).
run_stats() {
  local feeder
  exec 3< <(printf '%s' "$1"; exec sleep 120 2>/dev/null)
  feeder=$!
  timeout 100 "$emu" "$image" --fast --quiet --stats --measure-from 0.3 --max-time "$2" <&3 2>&1 >/dev/null
  kill "$feeder" 2>/dev/null
  exec 3<&-
}
stats=$(run_stats $'STX#4#SET#1#3#0#4#ETX\nSTX#6#STM#1#1#256#0#100#102#ETX\n' 0.8)
window=$(grep -o 'steps [0-9]* [0-9]* [0-9]*' <<<"$stats")
entries=$(grep -o 'exception 35: [0-9]* entries' <<<"$stats" | grep -o '[0-9]* entries' | grep -o '[0-9]*')
per_entry=$(grep -o 'exception 35: [0-9]* entries, [0-9.]* cycles each' <<<"$stats" | grep -o '[0-9.]* cycles each' | grep -o '^[0-9]*')
read -r _ steps other1 other2 <<<"$window"
echo "window: $window; TC4 entries $entries, $per_entry cycles each"
if [[ -z $entries || -z $steps ]]; then echo "FAIL: no figures from hmc-emu:"; echo "$stats"; exit 1; fi
# 0.5 s at 10 000 steps/s: 5 000 steps, one interrupt each (±1 at the window's edges).
if (( steps < 4990 || steps > 5010 || other1 != 0 || other2 != 0 )); then
  echo "FAIL: expected about 5000 steps of motor 1 alone"; exit 1
fi
if (( entries < steps - 1 || entries > steps + 1 )); then
  echo "FAIL: $entries step interrupts for $steps steps (expected one each)"; exit 1
fi
if (( per_entry >= 4800 )); then echo "FAIL: an interrupt of $per_entry cycles outlasts its 4 800-cycle period"; exit 1; fi
pulses=$(grep -o 'STEP 1: [0-9]* pulses, high [0-9.]*-[0-9.]* ns, low >= [0-9.-]* ns, period [0-9.]*-[0-9.]* ns' <<<"$stats")
echo "$pulses"
read -r high_min high_max low_min period_min period_max < <(sed -E 's/.*high ([0-9.]+)-([0-9.]+) ns, low >= ([0-9.-]+) ns, period ([0-9.]+)-([0-9.]+) ns/\1 \2 \3 \4 \5/' <<<"$pulses")
if [[ -z $period_max ]]; then echo "FAIL: no STEP pulse figures from hmc-emu"; exit 1; fi
if ! awk -v a="$high_min" -v b="$high_max" 'BEGIN { exit !(a >= 1999 && b <= 2001) }'; then
  echo "FAIL: STEP high $high_min-$high_max ns, expected 2000 (the DMA's clear 96 ticks after the rise)"; exit 1
fi
if ! awk -v a="$low_min" 'BEGIN { exit !(a >= 1900) }'; then echo "FAIL: STEP low $low_min ns < 1900"; exit 1; fi
if ! awk -v a="$period_min" -v b="$period_max" 'BEGIN { exit !(a >= 99999 && b <= 100001) }'; then
  echo "FAIL: STEP rises $period_min-$period_max ns apart, expected 100 000 (each at its compare)"; exit 1
fi

stats=$(run_stats $'STX#4#SET#1#3#40000#68#ETX\nSTX#6#STM#1#1#256#0#25#27#ETX\n' 1.2)
pulses=$(grep -o 'STEP 1: [0-9]* pulses, high [0-9.]*-[0-9.]* ns' <<<"$stats")
echo "ramping: $pulses"
read -r ramp_pulses high_min high_max < <(sed -E 's/.*: ([0-9]+) pulses, high ([0-9.]+)-([0-9.]+) ns/\1 \2 \3/' <<<"$pulses")
if [[ -z $high_max ]] || ((ramp_pulses < 20000)); then echo "FAIL: no ramp of motor 1:"; echo "$stats"; exit 1; fi
if ! awk -v a="$high_min" -v b="$high_max" 'BEGIN { exit !(a >= 1999 && b <= 2001) }'; then
  echo "FAIL: ramping, STEP high $high_min-$high_max ns, expected 2000"; exit 1
fi
echo "ok"
