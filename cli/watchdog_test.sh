#!/usr/bin/env bash
# The link watchdog end to end: the real `hmc` against the real `hmc-sim` over TCP, in real time.
#  - `hmc run` of a long motion file killed with SIGKILL: the board brakes every motor within
#    the watchdog's time (hmc-sim's trace: the last line received, then EVD how 6), and the
#    next connection's status says the watchdog fired;
#  - the same when the TCP connection is cut under a live `hmc move --wait` (a relay is killed);
#  - a clean exit disarms it: a one-shot `move --run` afterwards keeps running;
#  - SIGHUP (a closed terminal) stops every motor as SIGTERM does (exit 130).
# Usage: watchdog_test.sh HMC_BINARY HMC_SIM_BINARY SOURCE_DIR
set -uo pipefail
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"
hmc_sim_src_args "$@"

watchdog_ms=300
ticks_per_ms=48000  # the simulated board's clock, 48 MHz

# json_of TEXT EXPRESSION: the expression's value on the JSON document TEXT (as d).
json_of() { python3 -c 'import json, sys; d = json.loads(sys.argv[1]); print(eval(sys.argv[2]))' "$1" "$2"; }

# watchdog_end: from the trace, "GAP_MS EVD_COUNT": the time from the last line the board
# received (keep-alives included) to the last EVD how 6 (watchdog), and how many motors it braked.
watchdog_end() {
  python3 - "$work/trace.jsonl" "$ticks_per_ms" <<'EOF'
import json, sys
last_rx, ends = None, []
for line in open(sys.argv[1]):
    e = json.loads(line)
    if e.get("ev") in ("rx", "rx_blank"):  # a frame, or a keep-alive
        last_rx = e["t"]
    elif e.get("ev") == "tx" and e["line"].startswith("STX#5#EVD#") and e["line"].split("#")[4] == "6":
        ends.append(e["t"])
if not ends or last_rx is None:
    print("none 0")
else:
    print(int((ends[-1] - last_rx) / int(sys.argv[2])), len(ends))
EOF
}

# all_idle: "yes" when hmc status --json shows every motor idle.
all_idle() {
  local status
  status=$("$hmc" --port "$port" status --json 2>/dev/null) || { echo "status failed"; return; }
  json_of "$status" '"yes" if all(m["state"] == "idle" for m in d["motors"]) else [m["state"] for m in d["motors"]]'
}

start_sim

# A long motion file: motors 1 and 3 together, many seconds at a constant rate.
cat >long.json <<'EOF'
{
  "hmc_motion": 1,
  "motors": {"pan": {"motor": 1}, "lift": {"motor": 3}},
  "steps": [
    {"together": [{"motor": "pan", "by": 40000, "speed": 4000}, {"motor": "lift", "by": 40000, "speed": 4000}]}
  ]
}
EOF

# 1. SIGKILL during `hmc run`.
"$hmc" --port "$port" --watchdog "$watchdog_ms" run long.json >run.out 2>&1 &
run_pid=$!
sleep 1.2
{ kill -9 "$run_pid" && wait "$run_pid"; } 2>/dev/null
sleep 0.8  # the watchdog's 300 ms, then the stop (constant rate: at once)
read -r gap braked <<<"$(watchdog_end)"
[[ $gap != none && $gap -le $((watchdog_ms + 20)) && $gap -ge $watchdog_ms ]] ||
  fail "SIGKILL: the watchdog braked $gap ms after the last line (want $watchdog_ms-$((watchdog_ms + 20)))"
[[ $braked == 2 ]] || fail "SIGKILL: $braked motors braked by the watchdog (want 2: pan and lift)"
idle=$(all_idle)
[[ $idle == yes ]] || fail "SIGKILL: motors not at rest after the watchdog: $idle"
status=$("$hmc" --port "$port" status 2>&1)
grep -q '^link watchdog: off; it FIRED' <<<"$status" || fail "SIGKILL: the next status does not say it fired: $status"
json=$("$hmc" --port "$port" status --json 2>/dev/null)
[[ $(json_of "$json" 'd["watchdog"]["fired"]') == True ]] || fail "SIGKILL: status --json watchdog: $json"

# 2. The TCP connection cut under a live `hmc move --wait`: a relay between hmc and the board,
# killed; hmc cannot stop anything any more, the board's watchdog must.
target=${port#tcp://}
python3 - "${target%:*}" "${target#*:}" >relay.out 2>&1 <<'EOF' &
import socket, sys, threading
listener = socket.socket()
listener.bind(("127.0.0.1", 0))
listener.listen(1)
print(listener.getsockname()[1], flush=True)
client, _ = listener.accept()
board = socket.create_connection((sys.argv[1], int(sys.argv[2])))
def pump(a, b):
    while True:
        data = a.recv(4096)
        if not data:
            break
        b.sendall(data)
threading.Thread(target=pump, args=(board, client), daemon=True).start()
pump(client, board)
EOF
relay_pid=$!
relay_port=
for _ in $(seq 100); do
  relay_port=$(head -1 relay.out 2>/dev/null)
  [[ -n $relay_port ]] && break
  sleep 0.05
done
"$hmc" --port "tcp://127.0.0.1:$relay_port" --watchdog "$watchdog_ms" move 3 --run --delay 500 --wait >cut.out 2>&1 &
cut_pid=$!
sleep 1.0
{ kill -9 "$relay_pid" && wait "$relay_pid"; } 2>/dev/null
wait "$cut_pid"
cut_exit=$?
sleep 0.8
[[ $cut_exit == 3 ]] || fail "cut link: hmc exit $cut_exit (want 3, the link was lost): $(cat cut.out)"
read -r gap braked <<<"$(watchdog_end)"
[[ $gap != none && $gap -le $((watchdog_ms + 20)) && $braked -ge 1 ]] ||
  fail "cut link: the watchdog braked $gap ms after the last line ($braked events)"
idle=$(all_idle)
[[ $idle == yes ]] || fail "cut link: motors not at rest: $idle"

# 3. A clean exit disarms it: a one-shot run afterwards keeps going well past the timeout.
"$hmc" --port "$port" --watchdog "$watchdog_ms" move 3 200 --delay 500 --wait >/dev/null 2>&1 ||
  fail "move --wait failed"
"$hmc" --port "$port" move 3 --run --delay 500 >/dev/null 2>&1 || fail "move --run failed"
sleep 1.0
json=$("$hmc" --port "$port" status --json 2>/dev/null)
[[ $(json_of "$json" 'd["motors"][2]["state"]') == moving ]] ||
  fail "after a clean exit, a one-shot move --run did not keep running: $json"
[[ $(json_of "$json" 'd["watchdog"]["timeout_ms"]') == 0 ]] || fail "the watchdog was left armed: $json"
"$hmc" --port "$port" stop >/dev/null 2>&1

# 4. SIGHUP stops every motor, as SIGTERM does.
"$hmc" --port "$port" move 3 --run --delay 500 --wait >hup.out 2>&1 &
hup_pid=$!
sleep 0.8
kill -HUP "$hup_pid"
wait "$hup_pid"
hup_exit=$?
[[ $hup_exit == 130 ]] || fail "SIGHUP: exit $hup_exit (want 130): $(cat hup.out)"
idle=$(all_idle)
[[ $idle == yes ]] || fail "SIGHUP: motors not at rest: $idle"

stop_sim
finish watchdog_test
