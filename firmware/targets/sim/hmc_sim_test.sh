#!/usr/bin/env bash
# Runs the real `hmc-sim` binary on each of its links (stdio, TCP, pseudo-terminal), with the
# control channel and a script, and checks the board's answers, exit codes and trace.
# Usage: hmc_sim_test.sh HMC_SIM_BINARY SOURCE_DIR BEHAVIOUR_SESSION_BINARY
set -uo pipefail
sim=$(realpath "$1")
src=$(realpath "$2")
session=$(realpath "$3")
# shellcheck source=SCRIPTDIR/../../../cli/sim_test_lib.sh
source "$src/cli/sim_test_lib.sh"

# frame NAME VALUES...: the frame with its length and checksum.
frame() {
  local name=$1 sum=0 body=
  shift
  for v in "$@"; do
    sum=$((sum + v))
    body+="#$v"
  done
  printf 'STX#%d#%s%s#%d#ETX' $(($# + 1)) "$name" "$body" $((sum % 256))
}

ack='STX#1#ACK#0#ETX'
# replies: the board's output without its events (names starting with E, docs/protocol.md).
replies() { grep -v '^STX#[0-9]*#E' || true; }
# nak REASON TOKEN OFFSET
nak() { frame NAK "$@"; }

# ---------------------------------------------------------------------------------------
# 1. stdio: the spec's 28 frames, in fast virtual time, answered in order exactly as the
# behaviour vectors spec-session and spec-session-legacy (conformance/vectors/behaviour_spec.json)
# say: the same vectors the simulated board is held to in behaviour_test.
vector() { "$session" "$src/conformance/vectors" "$1" "$2"; }
out=$(timeout 20 "$sim" --fast --no-self-test <"$src/examples/spec-frames.txt")
check "stdio exit code" 0 $?
check_match "stdio boot event" '^STX#3#EVB#7#100#107#ETX$' "$out"
check_match "stdio boot event: reset cause power-on" '^STX#6#EVR#1#0#0#0#0#1#ETX$' "$out"
out_sw=$(timeout 20 "$sim" --fast --no-self-test --reset-cause software <<<$'STX#2#STA#7#7#ETX\nSTX#2#STA#8#8#ETX')
check_match "--reset-cause software: EVR" '^STX#6#EVR#5#0#0#0#0#5#ETX$' "$out_sw"
check_match "--reset-cause software: STA 8 answers STR" '^STX#6#STR#5#0#0#0#0#5#ETX$' "$out_sw"
check_match "STA 7 still answers STW (the link watchdog, off)" '^STX#3#STW#0#0#0#ETX$' "$out_sw"
timeout 5 "$sim" --reset-cause fault </dev/null >/dev/null 2>&1
check "--reset-cause fault is refused (a simulated board has no fault record)" 2 $?
out=$(replies <<<"$out")
check "stdio spec-frames answers (vector spec-session)" "$(vector spec-session replies)" "$out"
out=$(timeout 20 "$sim" --fast --no-self-test --legacy <"$src/examples/spec-frames.txt" | replies)
check "stdio legacy answers (vector spec-session-legacy)" "$(vector spec-session-legacy replies)" "$out"

out=$(timeout 20 "$sim" --fast --no-self-test --seed <"$src/examples/spec-frames.txt")
check "stdio seed is silent" "" "$out"

# Real time, with the self-test: the answer comes after the boot's half turn and back.
out=$(printf '%s\n' "$(frame SVM 1 10)" | timeout 20 "$sim" | replies)
check "stdio real time" "$ack" "$out"

# ---------------------------------------------------------------------------------------
# 2. TCP: one client after another; the board keeps running between them.
start spec --tcp 127.0.0.1:0 --no-self-test
if port=$(tcp_port spec); then
  # A plain network session with the spec's frames, in real time at 115 200 baud.
  out=$(vector spec-session input | timeout 10 nc -q1 127.0.0.1 "$port" | replies)
  check "tcp spec-frames answers (vector spec-session)" "$(vector spec-session replies)" "$out"
fi
stopped spec TERM

start tcp --tcp 127.0.0.1:0 --no-self-test
if port=$(tcp_port tcp); then
  out=$(printf '%s\n' "$(frame SVM 1 10)" 'STX#6#STM#3#1#1#11#1000#238#ETX' "$(frame STM 3 1 16 0 500)" |
    timeout 10 nc -q1 127.0.0.1 "$port" | replies)
  check "tcp first client" "$(printf '%s\n%s\n%s' "$ack" "$(nak 8 8 24)" "$ack")" "$out"
  # Motor 3 still runs: homing is refused, motors_running (12), token 4 (dir), byte 12.
  out=$(printf '%s\n' "$(frame STM 1 3 0 0 0)" | timeout 10 nc -q1 127.0.0.1 "$port" | replies)
  check "tcp second client" "$(nak 12 4 12)" "$out"
  # A client that closes its sending side gets its answers, then the connection closes.
  out=$(printf '%s\n' "$(frame STM 3 0 0 0 0)" | timeout 10 nc -N 127.0.0.1 "$port" | replies)
  check "tcp half-closed client" "$ack" "$out"
fi
stopped tcp TERM
check_match "tcp notes" 'client 127\.0\.0\.1:[0-9]+ connected' "$(cat "$work/tcp.err")"

# ---------------------------------------------------------------------------------------
# 3. Pseudo-terminal: opened, answered, closed, opened again.
start pty --pty --no-self-test
if dev=$(announced pty 's/^hmc-sim: pty \(\/dev\/.*\)$/\1/p'); then
  stty -F "$dev" raw -echo
  for round in 1 2; do
    exec 3<>"$dev"
    printf '%s\n' "$(frame LED 2 0 0 "$round" 0)" >&3
    # The first whole line that is not an event: an opener may come in while the board is in
    # the middle of a line, as on a real port. Not bash's `read`: on a raw terminal it takes all
    # that has arrived and keeps only its first line.
    line=$(timeout 10 grep -m1 -E '^STX#[0-9]+#[^E]' <&3)
    exec 3>&-
    check "pty round $round" "$ack" "$line"
  done
fi
stopped pty INT

# ---------------------------------------------------------------------------------------
# 4. Control channel: a pressed switch refuses a move toward it.
start control --tcp 127.0.0.1:0 --control 127.0.0.1:0 --no-self-test --quiet
if port=$(tcp_port control) && cport=$(control_port control); then
  out=$(printf 'press 1 1\nbogus\npress 3 0\n' | timeout 10 nc -q1 127.0.0.1 "$cport")
  check_match "control answers" '^ok
error: unknown command .bogus.*
error: motor .3.: only motors 1 and 2 have limit switches$' "$out"
  toward_switch=$(frame STM 1 1 16 100 500)
  # limit_pressed (11), token 4 (dir), byte 12.
  out=$(printf '%s\n' "$toward_switch" | timeout 10 nc -q1 127.0.0.1 "$port" | replies)
  check "control press refuses the move" "$(nak 11 4 12)" "$out"
  out=$(printf 'status\n' | timeout 10 nc -q1 127.0.0.1 "$cport")
  check_match "control status" \
    '^\{"t":[0-9]+,"emergency":false,"motors":\[\{"motor":1,"pos":204800,.*"switches":\[false,true\]' "$out"
  out=$(printf 'auto 1 1\n' | timeout 10 nc -q1 127.0.0.1 "$cport")
  check "control auto" "ok" "$out"
  out=$(printf '%s\n' "$toward_switch" | timeout 10 nc -q1 127.0.0.1 "$port" | replies)
  check "control released switch allows the move" "$ack" "$out"
fi
stopped control TERM
check "control quiet" "" "$(grep -v 'listening on' "$work/control.err")"

# ---------------------------------------------------------------------------------------
# 5. Usage errors exit 2 with a message; a file that cannot be read exits 3.
usage() {
  local out code
  out=$(timeout 10 "$sim" "$@" 2>&1 </dev/null)
  code=$?
  check "usage exit code: $*" 2 "$code"
  check_match "usage message: $*" "$1" "$out"
}
usage --accel 4:100
usage --axis 1:5:3:0
usage --tcp nohost
usage --tcp 127.0.0.1:0 --pty
usage --baud fast
usage --frobnicate
printf 'at 1s estop\nat 2s press 3 0\n' >"$work/bad.script"
out=$(timeout 10 "$sim" --script "$work/bad.script" 2>&1 </dev/null)
check "bad script exit code" 2 $?
check "bad script message" "hmc-sim: $work/bad.script:2: motor '3': only motors 1 and 2 have limit switches" "$out"
out=$(timeout 10 "$sim" --script "$work/missing.script" 2>&1 </dev/null)
check "missing script exit code" 3 $?
check_match "missing script message" "cannot read script" "$out"

# ---------------------------------------------------------------------------------------
# 6. A script's emergency stop halts a running motor: at most one rising edge after it.
cat >"$work/estop.script" <<EOF
# motor 3 runs until stopped; the emergency switch is pressed 100 ms later
at 0s send $(frame STM 3 1 16 0 500)
at 100ms estop
EOF
out=$(timeout 20 "$sim" --fast --no-self-test --script "$work/estop.script" --trace "$work/estop.jsonl" \
  --tcp 127.0.0.1:0 --exit-when-idle 2>/dev/null)
check "estop script exit code" 0 $?
trace=$(cat "$work/estop.jsonl")
check_match "estop trace has the emergency" '^\{"t":4800000,"ev":"emergency","pressed":true\}$' "$trace"
before=$(awk '/"ev":"emergency"/ {exit} /"ev":"step","motor":3/ {n++} END {print n + 0}' <<<"$trace")
after=$(awk '/"ev":"emergency"/ {seen = 1; next} seen && /"ev":"step"/ {n++} END {print n + 0}' <<<"$trace")
check_match "estop: motor 3 stepped before it ($before steps)" '^[1-9][0-9]{2}$' "$before"
check_match "estop: at most one step after it ($after)" '^[01]$' "$after"

echo "$((checks - failures)) passed, $failures failed"
[[ $failures -eq 0 ]]
