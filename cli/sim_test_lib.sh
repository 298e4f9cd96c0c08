# shellcheck shell=bash
# Shared by the shell tests of hmc and hmc-sim (sourced, not run): a work directory (the current
# one) removed on exit with every process in $pids and $sim_pid, failure counting, the checks,
# and starting/stopping one hmc-sim over TCP (those need $sim, the hmc-sim binary).
started_in=$PWD
work=$(mktemp -d)
cd "$work" || exit 1
export HMC_SIM_STATE=$work/state
unset HMC_PORT
failures=0
checks=0
sim_pid=
pids=()

# Stops what is still running, and what it started (`hmc sim` runs hmc-sim as its child).
cleanup() {
  local pid child
  for pid in ${sim_pid:+"$sim_pid"} "${pids[@]}"; do
    for child in $(pgrep -P "$pid" 2>/dev/null); do kill -9 "$child" 2>/dev/null; done
    kill -9 "$pid" 2>/dev/null
  done
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

fail() {
  failures=$((failures + 1))
  printf 'FAIL %s\n' "$*"
}

# check NAME WANT GOT: GOT equals WANT.
check() {
  checks=$((checks + 1))
  [[ $2 == "$3" ]] || fail "$(printf '%s:\n  want: %s\n  got:  %s' "$1" "$2" "$3")"
}

# check_match NAME PATTERN TEXT: TEXT matches the extended regex PATTERN.
check_match() {
  checks=$((checks + 1))
  grep -Eq -- "$2" <<<"$3" || fail "$(printf '%s: no match for %s in:\n%s' "$1" "$2" "$3")"
}

# expect NAME WANT_EXIT PATTERN -- COMMAND...: the command exits WANT_EXIT and its combined
# output matches the extended regex PATTERN.
expect() {
  local name=$1 want_exit=$2 pattern=$3
  shift 4
  local out code
  out=$("$@" 2>&1)
  code=$?
  checks=$((checks + 1))
  if [[ $code -ne $want_exit ]] || ! grep -Eq -- "$pattern" <<<"$out"; then
    fail "$(printf '%s: exit %s (want %s), output:\n%s' "$name" "$code" "$want_exit" "$out")"
  fi
}

# hmc_sim_src_args "$@": a test run as TEST HMC_BINARY HMC_SIM_BINARY SOURCE_DIR checks those
# (usage and exit 2 otherwise) and gets them as $hmc, $sim and $src, absolute.
# shellcheck disable=SC2034  # $hmc and $src are the sourcing test's
hmc_sim_src_args() {
  cd "$started_in" || exit 1
  if [[ $# -ne 3 || ! -x $1 || ! -x $2 || ! -d $3 ]]; then
    echo "usage: $0 HMC_BINARY HMC_SIM_BINARY SOURCE_DIR" >&2
    exit 2
  fi
  hmc=$(realpath "$1")
  sim=$(realpath "$2")
  src=$(realpath "$3")
  cd "$work" || exit 1
}

# require_built FILE...: the firmware preset's files the test runs on. Without one the test is
# skipped (exit 77), unless CI=true: there it must have been built, and its absence fails.
require_built() {
  local file
  for file in "$@"; do
    [[ -f $file ]] && continue
    if [[ ${CI:-} == true ]]; then
      echo "FAIL: no $file (build the firmware preset first)"
      exit 1
    fi
    echo "SKIP: no $file (cmake --preset firmware && cmake --build --preset firmware)"
    exit 77
  done
}

# --- hmc-sim processes of the test's own (several at once, each its own stderr) ---------------

# ms: the wall clock in milliseconds.
ms() { echo $(($(date +%s%N) / 1000000)); }

# start NAME ARGS...: runs hmc-sim in the background, stderr to $work/NAME.err; sets $pid.
start() {
  local name=$1
  shift
  "$sim" "$@" 2>"$work/$name.err" &
  pid=$!
  pids+=("$pid")
}

# announced NAME SED_EXPRESSION: waits (10 s at most, while the process $pid runs) for a line on
# NAME's stderr and prints what the expression extracts from it.
announced() {
  local found
  for _ in $(seq 200); do
    found=$(sed -n "$2" "$work/$1.err" 2>/dev/null)
    if [[ -n $found ]]; then
      echo "$found"
      return 0
    fi
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  echo "($1 said where it listens nowhere on its standard error: $(cat "$work/$1.err" 2>/dev/null))" >&2
  return 1
}
tcp_port() { announced "$1" 's/^hmc-sim: listening on tcp:\/\/127\.0\.0\.1:\([0-9]*\)$/\1/p'; }
control_port() { announced "$1" 's/^hmc-sim: control listening on tcp:\/\/127\.0\.0\.1:\([0-9]*\)$/\1/p'; }

# await_exit PID SECONDS: waits at most SECONDS for PID to end and sets $finished to its exit code
# (124, after killing it, when it did not end in time).
await_exit() {
  local deadline=$(($(ms) + $2 * 1000))
  while kill -0 "$1" 2>/dev/null && (($(ms) < deadline)); do sleep 0.02; done
  if kill -0 "$1" 2>/dev/null; then
    kill -9 "$1" 2>/dev/null
    wait "$1" 2>/dev/null
    finished=124
    return
  fi
  wait "$1" 2>/dev/null
  finished=$?
}

# stopped NAME SIGNAL: stops the hmc-sim NAME ($pid) with SIGNAL and checks it exits 0 (which
# also writes out its trace).
stopped() {
  kill "-$2" "$pid" 2>/dev/null
  await_exit "$pid" 10
  check "$1: hmc-sim's exit code after SIG$2" 0 "$finished"
}

# --- one hmc-sim over TCP with a trace ------------------------------------------------------

# Starts hmc-sim on a free TCP port with a trace in $work/trace.jsonl (extra options are passed
# on); sets $port.
start_sim() {
  # Emptied here, not only by the redirection below: that runs in the child, and until it does
  # the file still names the last simulator's port.
  : >"$work/sim.err"
  "$sim" --tcp 127.0.0.1:0 --no-self-test --trace "$work/trace.jsonl" "$@" 2>"$work/sim.err" &
  sim_pid=$!
  port=
  for _ in $(seq 100); do
    port=$(grep -o 'tcp://[0-9.:]*' "$work/sim.err" | head -1)
    [[ -n $port ]] && return 0
    sleep 0.05
  done
  fail "hmc-sim did not start: $(cat "$work/sim.err")"
  exit 1
}

# Stops hmc-sim cleanly, so that its trace is complete.
stop_sim() {
  kill -TERM "$sim_pid" 2>/dev/null
  wait "$sim_pid" 2>/dev/null
  sim_pid=
}

# Ends the test: exit status 1 if anything failed.
finish() {
  if ((failures > 0)); then
    echo "$1: $failures failures"
    exit 1
  fi
  echo "$1: all checks passed${2:+ ($2)}"
}
