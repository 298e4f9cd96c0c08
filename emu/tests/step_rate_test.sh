#!/usr/bin/env bash
# The spec's fastest frames on the real image in hmc-emu: the three 20 us moves sent together
# (STX#6#STM#1#1#8#0#20#30#ETX and the same for motors 2 and 3, 150 000 steps/s in all, the step
# budget at constant rate: firmware/core/protocol_facts.h, from the measured cycles): all three
# are accepted. The axes of motors 1 and 2 are wide enough that no switch is reached (motor 3
# has none); over one second of virtual time each makes 50 000 ± 1 steps (hmc-emu's window starts
# at the first chunk boundary after 0.3 s: the count is compared with 50 000 a second over the
# window it reports), every pulse made by the DMA 2.0 µs high and each rise exactly 20 µs after
# the one before (each motor on its own compare: step_timer.h).
# Usage: step_rate_test.sh HMC_EMU IMAGE_DIR
# Without the images the test is skipped (77), unless CI=true.
set -uo pipefail
emu=$(realpath "$1")
image=$(realpath -m "$2")/hmc-firmware.elf
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$image"
# Standard input stays open until --max-time ends the run (at its end hmc-emu would stop early).
exec 3< <(printf 'STX#6#STM#1#1#8#0#20#30#ETX\nSTX#6#STM#2#1#8#0#20#31#ETX\nSTX#6#STM#3#1#8#0#20#32#ETX\n'
          exec sleep 120 2>/dev/null)
feeder=$!
timeout 100 "$emu" "$image" --fast --quiet --stats --measure-from 0.3 --max-time 1.3 \
  --axis 1:0:200000000:100000000 --axis 2:0:200000000:100000000 <&3 >"$work/out" 2>"$work/err"
kill "$feeder" 2>/dev/null
exec 3<&-
replies=$(grep -c . "$work/out")
window=$(grep -o 'steps [0-9]* [0-9]* [0-9]*' "$work/err")
read -r from to < <(grep -o 'measured from [0-9.]* s to [0-9.]* s' "$work/err" | awk '{print $3, $6}')
# The three step interrupts' share of the CPU (TCC1, TCC2, TC4: exceptions 32, 33, 35).
share=$(grep -oE 'exception 3[235]: [0-9]* entries, [0-9.]* cycles each, [0-9]* cycles \([0-9.]* %' "$work/err" |
        grep -oE '[0-9.]+ %' | awk '{ s += $1 } END { if (NR == 3) printf "%.2f %%", s }')
read -r _ m1 m2 m3 <<<"$window"
echo "replies: $(tr '\n' ' ' <"$work/out"); window 0.3-1.3 s: $window; step interrupt: ${share:-?} of the CPU"
if [[ -z $m1 ]]; then echo "FAIL: no figures from hmc-emu:"; cat "$work/err"; exit 1; fi
# Replies in order (events aside): three ACKs.
want='STX#1#ACK#0#ETX
STX#1#ACK#0#ETX
STX#1#ACK#0#ETX'
if [[ $(grep -v '^STX#[0-9]*#EV' "$work/out" | head -3) != "$want" ]]; then
  echo "FAIL: expected ACK for motors 1, 2 and 3 ($replies lines)"
  exit 1
fi
expected=$(awk -v a="$from" -v b="$to" 'BEGIN { printf "%.1f", (b - a) * 50000 }')
counts=("$m1" "$m2" "$m3")
for motor in 1 2 3; do
  n=${counts[motor - 1]}
  echo "motor $motor: $n steps from $from s to $to s, $expected at 50 000 a second"
  if ! awk -v n="$n" -v e="$expected" 'BEGIN { exit !(n - e <= 1 && e - n <= 1) }'; then
    echo "FAIL: motor $motor: expected 50 000 ± 1 steps a second"; exit 1
  fi
  # The DMA's pulses (step_pulses.h): 2.0 us high, each rise exactly 20 us after the one before.
  pulses=$(grep -o "STEP $motor: [0-9]* pulses, high [0-9.]*-[0-9.]* ns, low >= [0-9.-]* ns, period [0-9.]*-[0-9.]* ns" "$work/err")
  echo "$pulses"
  read -r high_min high_max low_min period_min period_max < <(sed -E 's/.*high ([0-9.]+)-([0-9.]+) ns, low >= ([0-9.-]+) ns, period ([0-9.]+)-([0-9.]+) ns/\1 \2 \3 \4 \5/' <<<"$pulses")
  if [[ -z $period_max ]] || ! awk -v a="$high_min" -v b="$high_max" -v l="$low_min" -v p="$period_min" -v q="$period_max" \
      'BEGIN { exit !(a >= 1999 && b <= 2001 && l >= 1900 && p >= 19999 && q <= 20001) }'; then
    echo "FAIL: motor $motor: expected STEP 2.0 us high, >= 1.9 us low, rises 20 000 ns apart"
    exit 1
  fi
done
echo "ok"
