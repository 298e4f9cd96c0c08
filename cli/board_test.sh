#!/usr/bin/env bash
# Runs the real `hmc` binary against the real `hmc-sim` (over TCP and a pseudo-terminal, as the
# seed firmware, and in-process as sim://) as a user would, and checks the board commands' output,
# exit codes and, through hmc-sim's trace, what reached the board.
# Usage: board_test.sh HMC_BINARY HMC_SIM_BINARY SOURCE_DIR
set -uo pipefail
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"
hmc_sim_src_args "$@"

# check_true NAME DETAIL COMMAND...: COMMAND succeeds (DETAIL is shown when it does not).
check_true() {
  local name=$1 detail=$2
  shift 2
  checks=$((checks + 1))
  "$@" || fail "$name: $detail"
}

# expect NAME WANT_EXIT PATTERN -- COMMAND...: the command exits WANT_EXIT (within 30 s) and its
# combined output matches the extended regex PATTERN. Sets $out (stdout only) for further checks
# (in place of sim_test_lib.sh's expect, which sets nothing).
expect() {
  local name=$1 want_exit=$2 pattern=$3 code
  shift 4
  timeout 30 "$@" >"$work/out" 2>"$work/err"
  code=$?
  out=$(cat "$work/out")
  local all
  all=$(cat "$work/out" "$work/err")
  checks=$((checks + 1))
  if [[ $code -ne $want_exit ]] || ! grep -Eq -- "$pattern" <<<"$all"; then
    fail "$(printf '%s: exit %s (want %s; pattern %s), command: %s\noutput:\n%s' \
      "$name" "$code" "$want_exit" "$pattern" "$*" "$all")"
  fi
}

# json TEXT PYTHON_EXPRESSION...: sets the array $got to each expression's value (as JSON) on the
# JSON document TEXT (as `d`), or to why it cannot be had (which then fails the check it goes to).
# One python3 for all: it takes a while to start.
json() {
  local text=$1
  shift
  mapfile -t got < <(python3 -c 'import json, sys
try:
    d = json.loads(sys.argv[1])
except ValueError as e:
    d = e
for x in sys.argv[2:]:
    try:
        if isinstance(d, Exception):
            raise d
        print(json.dumps(eval(x)))
    except Exception as e:
        print("(%s: %r, in %s)" % (x, e, sys.argv[1].replace("\n", " ")))' "$text" "$@")
}

# control PORT COMMAND: sends one command on hmc-sim's control channel, prints the answer line.
control() {
  local answer=
  exec 5<>"/dev/tcp/127.0.0.1/$1" || return 1
  printf '%s\n' "$2" >&5
  IFS= read -r -t 5 answer <&5
  exec 5>&-
  printf '%s\n' "$answer"
}

# in_state CONTROL_PORT MOTOR STATE [PID]: waits (10 s at most, while PID runs) until the board
# says the motor is in STATE (hmc-sim's control status: idle, moving, ...).
in_state() {
  for _ in $(seq 200); do
    control "$1" status | grep -Eq "\"motor\":$2,[^}]*\"state\":\"$3\"" && return 0
    [[ -n ${4:-} ]] && ! kill -0 "$4" 2>/dev/null && return 1
    sleep 0.05
  done
  return 1
}
moving() { in_state "$1" "$2" moving "${3:-}"; }
idle() { in_state "$1" "$2" idle; }

# position_units OUTPUT: "motor 1: done, at 800 steps of 1/16 ..." -> 800 * 256 / 16 (1/256 step).
position_units() {
  local steps micro
  steps=$(sed -n 's/.* at \(-\{0,1\}[0-9]*\) steps of 1\/\([0-9]*\) .*/\1/p' <<<"$1" | head -1)
  micro=$(sed -n 's/.* at \(-\{0,1\}[0-9]*\) steps of 1\/\([0-9]*\) .*/\2/p' <<<"$1" | head -1)
  [[ -n $steps && -n $micro ]] && echo $((steps * 256 / micro)) || echo "(no position in: $1)"
}

t_begin=$(ms)

# ---------------------------------------------------------------------------------------
# 1. TCP, fast virtual time: every command once.
start tcp --tcp 127.0.0.1:0 --control 127.0.0.1:0 --no-self-test --fast --trace "$work/tcp.jsonl"
if port=$(tcp_port tcp) && cport=$(control_port tcp); then
  board=tcp://127.0.0.1:$port

  expect send-frame 0 '^ACK \(reply\): accepted$' -- "$hmc" -p "$board" send 'STX#3#SVM#1#135#136#ETX'
  expect send-notation 0 '^ACK \(reply\): accepted$' -- "$hmc" -p "$board" send '[#SVM#1#135]'
  expect send-words 0 '^ACK \(reply\): accepted$' -- "$hmc" send SVM 1 135 --port "$board"
  expect send-query 0 '^VER \(reply\): protocol 7' -- "$hmc" -p "$board" send VER
  expect send-json 0 '^\{"reply":\{"name":"ACK"\}\}$' -- "$hmc" -p "$board" --json send SVM 2 90
  expect send-board-line 0 '^board: tcp 127\.0\.0\.1:[0-9]+, firmware [0-9.]+, protocol 7$' -- \
    "$hmc" -p "$board" send SVM 1 90
  # Protocol 4: why the board last reset (hmc-sim: power-on), in words and in JSON.
  expect status-last-reset 0 '^last reset: power-on$' -- "$hmc" -p "$board" status
  expect status-last-reset-json 0 '"last_reset": \{' -- "$hmc" -p "$board" status --json
  expect send-reset-query 0 '^STR \(reply\): last reset: power-on$' -- "$hmc" -p "$board" send STA 8
  expect send-watchdog-query 0 '^STW \(reply\): link watchdog off' -- "$hmc" -p "$board" send STA 7
  expect monitor-last-reset 0 "^the board's last reset: power-on$" -- "$hmc" -p "$board" monitor --duration 0.2

  # move --wait prints where the motor stopped; status agrees (JSON positions in 1/256 step).
  expect move-wait 0 '^motor 1: done, at 800 steps of 1/16 \(50 full steps\)$' -- \
    "$hmc" -p "$board" move 1 800 --delay 100 --wait
  want=$(position_units "$out")
  expect status-json 0 '.' -- env HMC_PORT="$board" "$hmc" status --json
  status=$out
  json "$status" 'd["motors"][0]["position"]' 'd["firmware"]' 'd["motors"][0]["state"]' 'd["servos"][1]["pulse_us"]'
  check "status --json: motor 1's position is the one move printed" "$want" "${got[0]:-}"
  check "status --json: firmware" '"v2"' "${got[1]:-}"
  check "status --json: motor 1 idle" '"idle"' "${got[2]:-}"
  check "status --json: servo 2 at 90 degrees" 1472 "${got[3]:-}"

  # --json: the motor as it ended; a completed move's target is where it stopped.
  expect move-wait-json 0 '"last_end":"completed"' -- "$hmc" -p "$board" move 2 160 --delay 100 --wait --json
  json "$out" 'd["motors"][0]["position"]' 'd["motors"][0]["target"]'
  check "move --wait --json: motor 2 at 160 steps of 1/16" 2560 "${got[0]:-}"
  check "move --wait --json: target of the completed move" 2560 "${got[1]:-}"

  # 90 degrees = 50 full steps = 800 steps of 1/16, from 800.
  expect move-deg 0 '^motor 1: done, at 1600 steps of 1/16 \(100 full steps\)$' -- \
    "$hmc" -p "$board" move 1 --deg 90 --delay 100 --wait
  expect move-rate 0 '^motor 2: done, at 260 steps of 1/16' -- "$hmc" -p "$board" move 2 100 --rate 20000 --wait
  expect move-accel 0 '^motor 3: done, at 3200 steps of 1/16 \(200 full steps\)$' -- \
    "$hmc" -p "$board" move 3 3200 --accel 8000 --delay 100 --wait
  expect move-no-wait 0 '^started: stepper 3 reverse' -- "$hmc" -p "$board" move 3 -1600 --delay 100
  check_true "move without --wait: motor 3 comes to rest" "it did not" idle "$cport" 3
  expect move-back 0 '^motor 3: done, at 1601 steps of 1/16' -- "$hmc" -p "$board" move 3 1 --delay 100 --wait

  expect home-1 0 '^motor 1: homed, at 0 steps of 1/16' -- "$hmc" -p "$board" home 1
  expect home-all 0 '^motor 1: homed.*
motor 2: homed, at 0 steps of 1/16' -- "$hmc" -p "$board" home all
  expect status-text 0 '^2 +idle +0 +0 +1/16 +0 +yes +reverse pressed$' -- "$hmc" -p "$board" status
  check_match "status text: motor 1 homed" '^1 +idle +0 +0 +1/16 +0 +yes +reverse pressed$' "$out"
  check_match "status text: motor 3" '^3 +idle +1601 +1601 +1/16 +0 +no +-$' "$out"
  check_match "status text: emergency switch" '^emergency switch: released$' "$out"

  expect move-run 0 '^started: stepper 3 forward until stopped' -- "$hmc" -p "$board" move 3 --run --delay 100
  expect stop-3 0 '^motor 3: stopped, at [0-9]+ steps of 1/16' -- "$hmc" -p "$board" stop 3
  expect stop-all 0 '^motor 1: stopped.*
motor 2: stopped.*
motor 3: stopped' -- "$hmc" -p "$board" stop
  expect stop-json 0 '"state":"idle"' -- "$hmc" -p "$board" stop --json

  expect servo 0 '^servo 1 \(pan\) to 45 degrees$' -- "$hmc" -p "$board" servo 1 45
  expect servo-json 0 '^\{"angle":120,"pulse_us":[0-9]+,"servo":2\}$' -- "$hmc" -p "$board" servo 2 120 --json
  expect led-values 0 '^LED strip 1 to R10 G20 B30 W40$' -- "$hmc" -p "$board" led 1 10 20 30 40
  expect led-hex 0 '^LED strip 2 to R255 G128 B0 W16$' -- "$hmc" -p "$board" led 2 '#ff800010'
  expect led-hex6 0 '^LED strip 1 to R1 G2 B3 W0$' -- "$hmc" -p "$board" led 1 '#010203'
  expect led-off 0 '^LED strip 1 to R0 G0 B0 W0$' -- "$hmc" -p "$board" led 1 off
  expect status-after 0 '^strip 2: #ff800010 \(r 255, g 128, b 0, w 16\)$' -- "$hmc" -p "$board" status
  check_match "status: strip 1 off" '^strip 1: #00000000 ' "$out"
  check_match "status: servo 1 at 45 degrees" '^servo 1 \(pan\): [0-9]+ us   servo 2 \(tilt\): [0-9]+ us$' "$out"
  expect status-json-again 0 '.' -- "$hmc" -p "$board" status --json
  json "$out" '[d["strips"][1][k] for k in "rgbw"]' '[m["homed"] for m in d["motors"]]'
  check "status --json: strip 2" '[255, 128, 0, 16]' "${got[0]:-}"
  check "status --json: motors 1 and 2 homed" '[true, true, false]' "${got[1]:-}"

  # monitor: a switch pressed on the board (the control channel) shows as an EVL event.
  "$hmc" -p "$board" monitor --duration 1 >"$work/monitor.out" 2>"$work/monitor.err" &
  mpid=$!
  pids+=("$mpid")
  for _ in $(seq 200); do grep -q '^listening' "$work/monitor.err" && break; sleep 0.05; done
  check "control: press 2 1" ok "$(control "$cport" 'press 2 1')"
  await_exit "$mpid" 15
  check "monitor exit code" 0 "$finished"
  check_match "monitor shows the switch" '^\+[0-9]+\.[0-9]{3} s  EVL event: motor 2 .*pressed' "$(cat "$work/monitor.out")"
  check "control: release 2 1" ok "$(control "$cport" 'release 2 1')"

  expect ports-json 0 '.' -- "$hmc" ports --json
  json "$out" 'isinstance(d, list)'
  check "ports --json is a JSON array" true "${got[0]:-}"
  expect ports-text 0 '.' -- "$hmc" ports
else
  fail "tcp: not started (no address on its standard error)"
fi
stopped tcp TERM
check_true "trace: the notation's frame reached the board" "no rx of STX#3#SVM#1#135#136#ETX in $work/tcp.jsonl" \
  grep -q '"ev":"rx","line":"STX#3#SVM#1#135#136#ETX"' "$work/tcp.jsonl"
check_true "trace: --accel set the motor's acceleration" "no rx of STX#4#SET#3#3#8000#... in $work/tcp.jsonl" \
  grep -q '"ev":"rx","line":"STX#4#SET#3#3#8000#' "$work/tcp.jsonl"

# ---------------------------------------------------------------------------------------
# 2. Pseudo-terminal: a move and status; a port another hmc holds is busy.
start pty --pty --no-self-test
if dev=$(announced pty 's/^hmc-sim: pty \(\/dev\/.*\)$/\1/p'); then
  expect pty-move 0 '^motor 2: done, at 400 steps of 1/16 \(25 full steps\)$' -- \
    "$hmc" -p "$dev" move 2 400 --delay 100 --wait
  expect pty-board 0 "^board: pseudo-terminal $dev, firmware" -- "$hmc" -p "$dev" status
  check_match "pty status: motor 2" '^2 +idle +400 +400 +1/16' "$out"

  "$hmc" -p "$dev" monitor --duration 3 >"$work/pty-monitor.out" 2>"$work/pty-monitor.err" &
  mpid=$!
  pids+=("$mpid")
  for _ in $(seq 200); do grep -q '^listening' "$work/pty-monitor.err" && break; sleep 0.05; done
  expect pty-busy 3 "$dev.*in use|in use.*$dev" -- "$hmc" -p "$dev" status
  await_exit "$mpid" 15
  check "pty: the monitor holding the port exits 0" 0 "$finished"
  expect pty-free-again 0 '^2 +idle +400 ' -- "$hmc" -p "$dev" status
else
  fail "pty: not started (no address on its standard error)"
fi
stopped pty TERM

# ---------------------------------------------------------------------------------------
# 3. Error paths.
expect no-such-port 3 'no such port /dev/ttyHMCNOPE' -- "$hmc" --port /dev/ttyHMCNOPE status
expect no-such-port-json 3 '"kind":"link"' -- "$hmc" --port /dev/ttyHMCNOPE status --json
expect nothing-listens 3 'tcp://127\.0\.0\.1:1' -- "$hmc" -p tcp://127.0.0.1:1 status
expect usage-motor 2 '.' -- "$hmc" -p tcp://127.0.0.1:1 move 9 10
expect usage-no-distance 2 'give the distance once' -- "$hmc" -p sim://usage?fast move 1
expect usage-led 2 'colour' -- "$hmc" -p sim://usage?fast led 1 '#12'

start errors --tcp 127.0.0.1:0 --no-self-test --fast
if port=$(tcp_port errors); then
  board=tcp://127.0.0.1:$port
  # The spec's example 5 (line 14 of its frames): its checksum is wrong; the board refuses it.
  example5=$(sed -n 14p "$src/examples/spec-frames.txt")
  check "spec example 5" 'STX#6#STM#3#1#1#11#1000#238#ETX' "$example5"
  expect refused-by-board 1 'checksum' -- "$hmc" -p "$board" send --raw "$example5"
  expect refused-by-board-json 1 '"kind":"refused_by_board","message":"[^"]*checksum' -- \
    "$hmc" -p "$board" --json send --raw "$example5"
  expect refused-by-codec 1 'microstep' -- "$hmc" -p "$board" send STM 1 1 3 1000 500
  # Motor 1 starts 12800 steps of 1/16 above its reverse switch: it stops there.
  expect limit 5 '^motor 1: ended early: limit, at -12800 steps of 1/16' -- \
    "$hmc" -p "$board" move 1 -20000 --delay 50 --wait
  expect host-refuses 1 'reverse end is pressed' -- "$hmc" -p "$board" move 1 -10
  expect host-refuses-json 1 '"kind":"refused".*"reason":"limit_pressed"' -- "$hmc" -p "$board" move 1 -10 --json
  expect away-from-switch 0 '^motor 1: done, at -12790 steps' -- "$hmc" -p "$board" move 1 10 --wait
else
  fail "errors: not started (no address on its standard error)"
fi
stopped errors TERM

# ---------------------------------------------------------------------------------------
# 4. The seed firmware: no replies, so the host times the move; no acceleration.
start seed --tcp 127.0.0.1:0 --control 127.0.0.1:0 --seed --no-self-test
if port=$(tcp_port seed) && cport=$(control_port seed); then
  board=tcp://127.0.0.1:$port
  # Silence is never success: without --firmware seed, a board that answers nothing is an error.
  expect seed-silent 4 'no reply to VER .*not a board, or it is not powered, or not at this baud rate.*--firmware seed' -- \
    "$hmc" -p "$board" move 1 400 --delay 1000 --wait
  check_match "seed: nothing was moved on silence" '"motor":1,"pos":204800,.*"state":"idle"' "$(control "$cport" status)"
  expect seed-status 0 'seed firmware' -- "$hmc" -p "$board" --firmware seed status
  expect seed-status-json 0 '"firmware": "seed"' -- "$hmc" -p "$board" --firmware seed status --json
  t0=$(ms)
  expect seed-move 0 '^motor 1: sent; the original firmware confirms nothing \(if it obeyed, it is 400 steps of 1/16 from where this hmc found it' -- \
    "$hmc" -p "$board" --firmware seed move 1 400 --delay 1000 --wait
  took=$(($(ms) - t0))
  check_true "seed move --wait took ${took} ms" "400 steps at 1000 us must take at least 400 ms" test "$took" -ge 400
  # When it returns, the board is done: 204800 + 400 * 16.
  check_match "seed: the motor rests where hmc says" '"motor":1,"pos":211200,.*"state":"idle"' \
    "$(control "$cport" status)"
  t0=$(ms)
  expect seed-move-given 0 'confirms nothing \(if it obeyed, it is 400 steps of 1/16 from where this hmc found it' -- \
    "$hmc" -p "$board" --firmware seed move 1 400 --delay 1000 --wait
  took=$(($(ms) - t0))
  check_true "seed move --wait (--firmware seed, no VER) took ${took} ms" "at least 400 ms" test "$took" -ge 400
  check_match "seed: the second move too" '"motor":1,"pos":217600,.*"state":"idle"' "$(control "$cport" status)"
  expect seed-no-accel 1 'seed firmware has no acceleration' -- "$hmc" -p "$board" --firmware seed move 1 400 --accel 8000
  expect seed-send 0 'sent \(the seed firmware does not reply\)' -- "$hmc" -p "$board" --firmware seed send SVM 1 90
  check_match "seed: the move with --accel was not sent" '"motor":1,"pos":217600,.*"state":"idle"' \
    "$(control "$cport" status)"
else
  fail "seed: not started (no address on its standard error)"
fi
stopped seed INT

# ---------------------------------------------------------------------------------------
# 5. The board goes away mid-move: hmc says so and exits 3 at once.
start gone --tcp 127.0.0.1:0 --control 127.0.0.1:0 --no-self-test
if port=$(tcp_port gone) && cport=$(control_port gone); then
  "$hmc" -p "tcp://127.0.0.1:$port" move 3 100000 --delay 100 --wait >"$work/gone.out" 2>&1 &
  hpid=$!
  pids+=("$hpid")
  check_true "disconnect: motor 3 moves" "the board never said so" moving "$cport" 3 "$hpid"
  sleep 0.3
  kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  t0=$(ms)
  await_exit "$hpid" 10
  took=$(($(ms) - t0))
  check "disconnect: exit code" 3 "$finished"
  check_true "disconnect: hmc ended ${took} ms after the board went" "want at most 2000 ms" test "$took" -le 2000
  check_match "disconnect: message" '^error: .*connection' "$(cat "$work/gone.out")"
else
  fail "gone: not started (no address on its standard error)"
fi

# ---------------------------------------------------------------------------------------
# 6. Ctrl-C during move --wait: every motor is sent a stop, and the board stops (the trace).
start ctrlc --tcp 127.0.0.1:0 --control 127.0.0.1:0 --no-self-test --trace "$work/ctrlc.jsonl"
if port=$(tcp_port ctrlc) && cport=$(control_port ctrlc); then
  "$hmc" -p "tcp://127.0.0.1:$port" move 3 100000 --delay 100 --wait >"$work/ctrlc.out" 2>&1 &
  hpid=$!
  pids+=("$hpid")
  check_true "ctrl-c: motor 3 moves" "the board never said so" moving "$cport" 3 "$hpid"
  sleep 0.3
  kill -INT "$hpid" 2>/dev/null
  await_exit "$hpid" 10
  check "ctrl-c: exit code" 130 "$finished"
  check_match "ctrl-c: says every motor was sent a stop" 'every motor was sent a stop' "$(cat "$work/ctrlc.out")"
  check_match "ctrl-c: says where motor 3 stopped" '^motor 3 stopped at [0-9]+ steps of 1/16' "$(cat "$work/ctrlc.out")"
  stopped ctrlc INT
  # After the stop reached the board (rx), motor 3 steps no more once its main loop has run
  # (1 ms = 48 000 ticks); it had made some steps, far fewer than the 100 000 asked.
  verdict=$(python3 - "$work/ctrlc.jsonl" <<'EOF'
import json, sys
events = [json.loads(line) for line in open(sys.argv[1])]
stops = [e["t"] for e in events if e["ev"] == "rx" and e["line"] == "STX#6#STM#3#0#0#0#0#3#ETX"]
steps = [e["t"] for e in events if e["ev"] == "step" and e["motor"] == 3]
if not stops:
    print("no rx event with STX#6#STM#3#0#0#0#0#3#ETX; rx lines: %s"
          % [e["line"] for e in events if e["ev"] == "rx"])
elif not 0 < len(steps) < 50000:
    print("motor 3 made %d steps (want 1-49999)" % len(steps))
else:
    late = [t for t in steps if t > stops[0] + 48000]
    print("ok" if not late else "%d steps of motor 3 more than 1 ms after the stop (t=%d), first at t=%d"
          % (len(late), stops[0], late[0]))
EOF
)
  check "ctrl-c: the trace shows motor 3 stopped" ok "$verdict"
else
  fail "ctrlc: not started (no address on its standard error)"
fi

# ---------------------------------------------------------------------------------------
# 7. sim://: the board inside hmc, kept between commands; `hmc sim` says how to connect.
expect sim-move 0 '^motor 1: done, at 3200 steps of 1/16 \(200 full steps\)$' -- \
  "$hmc" --port sim:// move 1 3200 --accel 8000 --wait
check_match "sim-move: 3200 steps" '3200 steps' "$out"
expect sim-status 0 '.' -- "$hmc" --port sim:// status --json
json "$out" 'd["motors"][0]["position"]'
check "sim:// status --json: motor 1 where the last command left it" 51200 "${got[0]:-}"
check_true "sim:// journal in HMC_SIM_STATE" "no $HMC_SIM_STATE/sim-default.journal" test -s "$HMC_SIM_STATE/sim-default.journal"

# Options after -- go to hmc-sim: without its self-test the motors rest at 0.
HMC_SIM_BIN=$sim "$hmc" sim --tcp 127.0.0.1:0 -- --no-self-test >"$work/hmc-sim.out" 2>"$work/hmc-sim.err" &
hpid=$!
pids+=("$hpid")
pid=$hpid
if connect=$(announced hmc-sim 's/^ *hmc --port \(tcp:\/\/127\.0\.0\.1:[0-9]*\) status$/\1/p'); then
  expect hmc-sim-connect 0 '^1 +idle +0 ' -- "$hmc" --port "$connect" status
else
  fail "hmc sim: not started (no address on its standard error)"
fi
# `hmc sim` ends when its hmc-sim does (Ctrl-C reaches both; here hmc-sim alone is told).
for child in $(pgrep -P "$hpid"); do kill -TERM "$child"; done
await_exit "$hpid" 10
check "hmc sim: exit code once hmc-sim ended" 0 "$finished"

t_total=$(($(ms) - t_begin))
echo "$((checks - failures)) passed, $failures failed ($t_total ms)"
[[ $failures -eq 0 ]]
