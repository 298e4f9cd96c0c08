#!/usr/bin/env bash
# The spec's fastest frames on hmc-sim: STX#6#STM#1#1#8#0#20#30#ETX and the same 20 µs frame for
# motors 2 and 3, sent together (150 000 steps/s in all): the constant-rate budget of
# firmware/core/protocol_facts.h (150 000 steps/s, from the image's measured cycles) takes all
# three. With axes wide enough that no switch is reached (motor 3 has none), the trace of each
# motor shows a step every 960 ticks (20 µs at 48 MHz) from its first to its last, and 50 000 ± 1
# steps in one second of virtual time.
# Usage: fastest_frames_test.sh HMC_SIM_BINARY
set -uo pipefail
sim=$(realpath "$1")
# shellcheck source=SCRIPTDIR/../../../cli/sim_test_lib.sh
source "$(dirname "$(realpath "${BASH_SOURCE[0]}")")/../../../cli/sim_test_lib.sh"

cat >script.txt <<'EOF'
at 100ms send STX#6#STM#1#1#8#0#20#30#ETX
at 100ms send STX#6#STM#2#1#8#0#20#31#ETX
at 100ms send STX#6#STM#3#1#8#0#20#32#ETX
at 1500ms send STX#6#STM#1#0#0#0#0#1#ETX
at 1500ms send STX#6#STM#2#0#0#0#0#2#ETX
at 1500ms send STX#6#STM#3#0#0#0#0#3#ETX
EOF
timeout 60 "$sim" --fast --no-self-test --quiet --axis 1:0:200000000:100000000 \
  --axis 2:0:200000000:100000000 --script script.txt --trace trace.jsonl --exit-when-idle \
  </dev/null >out.txt 2>err.txt
check "hmc-sim exit code" 0 $?
replies=$(grep -v '^STX#[0-9]*#E' out.txt | tr '\n' ' ')
check "the three moves and the stops accepted" \
  "STX#1#ACK#0#ETX STX#1#ACK#0#ETX STX#1#ACK#0#ETX STX#1#ACK#0#ETX STX#1#ACK#0#ETX STX#1#ACK#0#ETX " "$replies"

# Per motor: the step times (ticks) must be 960 apart, every one; the window is one second (48e6
# ticks) from 0.3 s, when all three run.
awk -F'[:,]' '
  /"ev":"step"/ {
    t = $2; m = $6
    if (m in last && t - last[m] != 960) { bad[m]++; if (!(m in first_bad)) first_bad[m] = t }
    last[m] = t; n[m]++
    if (t >= 14400000 && t < 62400000) window[m]++
  }
  END {
    for (m = 1; m <= 3; m++)
      printf "%d %d %d %d %s\n", m, n[m] + 0, window[m] + 0, bad[m] + 0, (m in first_bad) ? first_bad[m] : "-"
  }' trace.jsonl >steps.txt
while read -r motor total window off first_off; do
  echo "motor $motor: $total steps, $window from 0.3 s to 1.3 s, $off intervals not 960 ticks"
  check "motor $motor: every interval 960 ticks (first off at tick $first_off)" 0 "$off"
  checks=$((checks + 1))
  ((window >= 49999 && window <= 50001)) || fail "motor $motor: $window steps in one second, want 50 000 ± 1"
  checks=$((checks + 1))
  ((total > 60000)) || fail "motor $motor: only $total steps in all"
done <steps.txt
check "three motors traced" 3 "$(wc -l <steps.txt)"

echo "$checks checks, $failures failures"
((failures == 0))
