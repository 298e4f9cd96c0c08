#!/usr/bin/env bash
# `hmc stream` through the real binary against hmc-sim at 115200 baud (bytes paced both ways):
# a clean stream of mixed frames, and one with a refusal in the middle — the board's trace must
# show that nothing after the lines already on their way was received, and that everything
# before the refused line was carried out.
# Usage: stream_test.sh HMC_BINARY HMC_SIM_BINARY SOURCE_DIR
set -uo pipefail
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"
hmc_sim_src_args "$@"

start_sim --baud 115200

# 200 mixed frames, all accepted.
head -200 "$src/bench/mixed-2000.txt" >clean.txt
out=$("$hmc" --port "$port" stream clean.txt 2>&1) || fail "clean stream: $out"
grep -q '^streamed 200 of 200 lines' <<<"$out" || fail "clean stream says: $out"

# Motor 1 into its reverse switch (the mixed frames lowered its max_rate: restore it), then a
# stream whose line 41 moves toward it.
"$hmc" --port "$port" send SET 1 4 50000 >/dev/null 2>&1
"$hmc" --port "$port" move 1 -20000 --delay 50 --wait >/dev/null 2>&1
{
  for i in $(seq 40); do echo "SVM 1 $((10 + i))"; done
  echo "STM 1 2 16 10 100"
  for i in $(seq 40); do echo "SVM 2 $((10 + i))"; done
} >refused.txt
out=$("$hmc" --port "$port" stream refused.txt 2>&1)
code=$?
[[ $code == 1 ]] || fail "stream with a refusal: exit $code, want 1: $out"
grep -Eq 'refused.txt:41 \(command 41\) was refused: motor 1.s limit switch at the reverse end is pressed' <<<"$out" ||
  fail "the refusal is not reported with its line: $out"
grep -Eq 'the 40 commands before it were carried out; [1-9][0-9]* more were already on their way' <<<"$out" ||
  fail "what ran is not reported: $out"
sent=$(grep -o 'streamed [0-9]* of 81' <<<"$out" | grep -o '[0-9]* of' | grep -o '[0-9]*')
stop_sim
# The board received exactly the lines sent: the 40 before the refused one, it, and those
# already on their way — nothing after.
counts=$(python3 - "$work/trace.jsonl" <<'PY'
import json, sys
rx = [json.loads(l)["line"] for l in open(sys.argv[1]) if '"ev":"rx"' in l]
at = max(i for i, l in enumerate(rx) if l.startswith("STX#6#STM#1#2#16#10#100#"))
before = 0
for l in reversed(rx[:at]):
    if not l.startswith("STX#3#SVM#1#"):
        break
    before += 1
after = sum(1 for l in rx[at + 1:] if l.startswith("STX#3#SVM#2#"))
print(before, after)
PY
)
read -r before after <<<"$counts"
[[ $before == 40 ]] || fail "the board received $before of the 40 lines before the refused one"
[[ $after == $((sent - 41)) ]] || fail "the board received $after lines after the refused one; hmc says it sent $((sent - 41))"
(( sent < 81 && sent > 41 )) || fail "the stream did not stop at the refusal with lines in flight: $sent lines sent"

finish stream_test "$sent of 81 lines sent, $((sent - 41)) after the refused one"
