#!/usr/bin/env bash
# Motion files through the real `hmc` binary: check, plan (with its SVG), run --dry-run, a file
# with five mistakes (five messages, nothing sent), a run on hmc-sim over TCP whose trace and
# final status match the plan, and a run interrupted with SIGINT (every motor stopped) then
# resumed with --from to the end of the file.
# Usage: motion_test.sh HMC_BINARY HMC_SIM_BINARY SOURCE_DIR
set -uo pipefail
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"
hmc_sim_src_args "$@"
# Motion files read the profile hmc uses: none here.
export XDG_CONFIG_HOME=$work/config
unset HMC_PROFILE

# --- check, plan, dry run ---------------------------------------------------------------------
for f in "$src"/examples/*.json; do
  out=$("$hmc" check "$f" 2>&1) || fail "check $f: $out"
  [[ $out == *": valid: "* ]] || fail "check $f says: $out"
done

# A value in mm that is no whole number of steps is rounded, and the check says where.
out=$("$hmc" check "$src/examples/camera-slider-mm.json" 2>&1 >/dev/null)
grep -q '^note: .*camera-slider-mm.json:16:46: .*12.3456 mm is 987.648 steps: rounded to 988$' <<<"$out" ||
  fail "check names no rounding: $out"

out=$("$hmc" plan "$src/examples/pan-tilt-scan.json" --plot "$work/plot.svg" --csv "$work/plot.csv" 2>&1) ||
  fail "plan: $out"
grep -q '<svg' "$work/plot.svg" || fail "plan --plot wrote no SVG"
[[ $(grep -c '<polyline' "$work/plot.svg") -ge 2 ]] || fail "the SVG has no velocity line per motor"
[[ $(head -1 "$work/plot.csv") == "t_s,motor,name,velocity" ]] || fail "CSV header: $(head -1 "$work/plot.csv")"

out=$("$hmc" run "$src/examples/home-then-together.json" --dry-run 2>&1) || fail "dry run: $out"
grep -Eq 'STX#6#STM#1#3#16#0#0#20#ETX' <<<"$out" || fail "dry run lists no homing frame: $out"
grep -Eq '^ *[0-9.]+ s +\[3\] +STX#6#STM#3#' <<<"$out" || fail "dry run lists no timed frame for step 3: $out"

# --- five mistakes: five messages, file:line:column, nothing sent --------------------------------
start_sim
out=$("$hmc" --port "$port" run "$src/cli/testdata/five-mistakes.json" 2>&1)
code=$?
[[ $code == 1 ]] || fail "five mistakes: exit $code, want 1"
for want in 'five-mistakes.json:4:38: \$.motors.pan.microstep: microstep 3 is not a power of two' \
            'five-mistakes.json:9:42: \$.steps\[1\].move.sped: unknown key .*did you mean .speed.' \
            'five-mistakes.json:10:24: \$.steps\[2\].move.motor: unknown motor .lift.' \
            'five-mistakes.json:11:34: \$.steps\[3\].servo.angle: angle 200 degrees is out of range' \
            'five-mistakes.json:12:38: \$.steps\[4\].move.to: position 6400 steps is above tilt.s max limit' \
            '^5 errors; nothing was sent$'; do
  grep -Eq -- "$want" <<<"$out" || fail "five mistakes: no line matching $want in:
$out"
done
[[ $(grep -c 'five-mistakes.json:' <<<"$out") == 5 ]] || fail "five mistakes: not exactly five messages:
$out"
stop_sim
if grep -q '"ev":"rx"' "$work/trace.jsonl"; then fail "five mistakes: the board received something"; fi

# --- a run on hmc-sim over TCP matches its plan ---------------------------------------------------
rm -f "$work/trace.jsonl"
start_sim --fast
out=$("$hmc" --port "$port" run "$src/examples/home-then-together.json" 2>&1) || fail "run: $out"
grep -q '^done: 4 steps' <<<"$out" || fail "run did not finish: $out"
status=$("$hmc" --port "$port" status --json 2>&1)
pos() { python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["motors"][int(sys.argv[1])-1]["position"])' "$1" <<<"$status"; }
[[ $(pos 1) == $((1600 * 16)) ]] || fail "motor 1 ends at $(pos 1), want $((1600 * 16))"
[[ $(pos 2) == $((4000 * 16)) ]] || fail "motor 2 ends at $(pos 2), want $((4000 * 16))"
[[ $(pos 3) == $((300 * 64)) ]] || fail "motor 3 ends at $(pos 3), want $((300 * 64))"
stop_sim
# Every STM the board received was carried out to the step (homing aside).
python3 - "$work/trace.jsonl" <<'PY' || fail "the trace does not match the frames sent"
import json, sys
rx, steps = [], {1: [], 2: [], 3: []}
for line in open(sys.argv[1]):
    e = json.loads(line)
    if e["ev"] == "rx" and "#STM#" in e["line"]:
        f = e["line"].split("#")
        rx.append((e["t"], int(f[3]), int(f[4]), int(f[6])))
    if e["ev"] == "step":
        steps[e["motor"]].append(e["t"])
bad = 0
for i, (t, motor, action, count) in enumerate(rx):
    if action not in (1, 2):
        continue
    until = next((r[0] for r in rx[i + 1:] if r[1] == motor), float("inf"))
    done = sum(1 for s in steps[motor] if t < s <= until)
    if done != count:
        print(f"motor {motor}: {done} steps for a move of {count}")
        bad += 1
sys.exit(1 if bad or not rx else 0)
PY

# --- interrupted, then resumed with --from --------------------------------------------------------
rm -f "$work/trace.jsonl"
start_sim
"$hmc" --port "$port" run "$src/examples/camera-slider.json" >"$work/run.out" 2>"$work/run.err" &
run_pid=$!
sleep 2.5
kill -INT "$run_pid"
wait "$run_pid"
code=$?
[[ $code == 130 ]] || fail "interrupted run: exit $code, want 130: $(cat "$work/run.err")"
grep -q 'every motor was sent a stop' "$work/run.err" || fail "interrupted run says: $(cat "$work/run.err")"
resume=$(grep -o 'resume with: hmc run .*' "$work/run.err")
from=$(grep -o -- '--from [0-9]*' <<<"$resume" | grep -o '[0-9]*$')
at=$(grep -o -- '--at [-0-9,]*' <<<"$resume" | cut -d' ' -f2)
[[ -n $from && $at == "-,-,0" ]] || fail "interrupted run gives no --from and --at -,-,0: $(cat "$work/run.err")"
status=$("$hmc" --port "$port" status --json 2>&1)
moving=$(python3 -c 'import json,sys; d=json.load(sys.stdin); print(sum(m["state"] != "idle" for m in d["motors"]))' <<<"$status")
[[ $moving == 0 ]] || fail "after the interruption $moving motors still move: $status"
out=$("$hmc" --port "$port" run "$src/examples/camera-slider.json" --from "${from:-1}" --at "${at:--,-,0}" 2>&1) ||
  fail "resume: $out"
grep -q '^done:' <<<"$out" || fail "resumed run did not finish: $out"
status=$("$hmc" --port "$port" status --json 2>&1)
[[ $(pos 3) == 0 ]] || fail "after resuming, the slider ends at $(pos 3), want 0 (where the file leaves it)"

# --- interrupted in step 1, resumed with --from 1 --at: the motors first go back to the start
cat >"$work/two-glides.json" <<'EOF'
{
  "hmc_motion": 1,
  "motors": {"slider": {"motor": 3}},
  "steps": [
    {"move": {"motor": "slider", "by": 8000, "speed": 4000}},
    {"move": {"motor": "slider", "by": -8000, "speed": 4000}}
  ]
}
EOF
"$hmc" --port "$port" run "$work/two-glides.json" >"$work/run1.out" 2>"$work/run1.err" &
run_pid=$!
sleep 1.0
kill -INT "$run_pid"
wait "$run_pid"
resume=$(grep -o 'resume with: hmc run .*' "$work/run1.err")
grep -q -- '--from 1 --at ' <<<"$resume" || fail "interrupted in step 1: resume line is '$resume'"
at=$(grep -o -- '--at [-0-9,]*' <<<"$resume" | cut -d' ' -f2)
out=$("$hmc" --port "$port" run "$work/two-glides.json" --from 1 --at "$at" 2>&1) || fail "resume from 1: $out"
status=$("$hmc" --port "$port" status --json 2>&1)
steps3=$(python3 -c 'import json,sys; print(round(json.load(sys.stdin)["motors"][2]["steps"]))' <<<"$status")
[[ $steps3 == "${at##*,}" ]] ||
  fail "resumed from step 1 with --at $at: the slider ends at $steps3 steps, want ${at##*,} (where the plan ends)"
out=$("$hmc" --port "$port" run "$work/two-glides.json" --from 1 --at 1,2 2>&1)
code=$?
[[ $code == 2 ]] && grep -q 'takes 3 values' <<<"$out" && ! grep -q '^board:' <<<"$out" ||
  fail "--at with 2 values: exit $code (want 2, before the port is opened): $out"
out=$("$hmc" --port "$port" run "$work/two-glides.json" --at x,y,z 2>&1)
[[ $? == 2 ]] || fail "--at x,y,z: want exit 2: $out"

# --- a resumed run ends exactly where an uninterrupted one ends, where rounding matters ---------
# Motor 3 starts 0.75 of a step off the file's whole steps (3 steps of 1/64 = 12/256); the file
# moves it by 1 degree (26.667 steps) twenty times, then back by half a degree. The plan counts
# from 1 and ends at 1 + 20 x 26.667 - 13.333 = 521; the motor stays 0.25 below: 520.75 steps of
# 1/16, 8332/256 of a full step. (Before, a resume went back to whole steps counted from 0.)
cat >"$work/creep.json" <<'EOF2'
{
  "hmc_motion": 1,
  "motors": {"pan": {"motor": 3, "gear_ratio": 3}},
  "steps": [
    {"repeat": {"count": 20, "steps": [{"move": {"motor": "pan", "by": {"deg": 1}, "speed": {"deg_per_s": 10}}}]}},
    {"move": {"motor": "pan", "by": {"deg": -0.5}, "speed": {"deg_per_s": 20}}}
  ]
}
EOF2
off_grid() {
  "$hmc" --port "$port" zero 3 >/dev/null 2>&1 || fail "zero 3 failed"
  "$hmc" --port "$port" move 3 3 --microstep 64 --wait >/dev/null 2>&1 || fail "move 3 3 --microstep 64 failed"
}
position3() { "$hmc" --port "$port" status --json 2>&1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["motors"][2]["position"])'; }
off_grid
out=$("$hmc" --port "$port" run "$work/creep.json" 2>&1) || fail "uninterrupted creep: $out"
whole=$(position3)
[[ $whole == 8332 ]] || fail "uninterrupted creep ends at $whole/256 steps, want 8332 (520.75 steps of 1/16)"
off_grid
"$hmc" --port "$port" run "$work/creep.json" >"$work/creep.out" 2>"$work/creep.err" &
run_pid=$!
# Interrupted in the middle, once step 8 (of 21) has started, however long the start took.
for _ in $(seq 200); do
  grep -q '^step 8 of' "$work/creep.err" && break
  sleep 0.05
done
kill -INT "$run_pid"
wait "$run_pid"
code=$?
[[ $code == 130 ]] || fail "interrupted creep: exit $code, want 130: $(cat "$work/creep.err")"
resume=$(grep -o 'resume with: hmc run .*' "$work/creep.err")
[[ $resume == *" --at -,-,0.75" ]] || fail "interrupted creep: resume line is '$resume', want --at -,-,0.75"
read -ra resume_args <<<"${resume#resume with: hmc run }"
out=$("$hmc" --port "$port" run "${resume_args[@]}" 2>&1) || fail "resumed creep: $out"
resumed=$(position3)
[[ $resumed == "$whole" ]] ||
  fail "resumed creep (${resume#resume with: }) ends at $resumed/256 steps, the uninterrupted run at $whole"
stop_sim

finish motion_test
