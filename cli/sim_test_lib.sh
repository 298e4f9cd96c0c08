# Shared by the shell tests that drive `hmc` against one hmc-sim over TCP (sourced, not run):
# a work directory removed on exit, failure counting, and starting/stopping the simulator.
# The caller sets $sim (the hmc-sim binary) first.
work=$(mktemp -d)
cd "$work" || exit 1
export HMC_SIM_STATE=$work/state
unset HMC_PORT
failures=0
sim_pid=

cleanup() {
  [[ -n $sim_pid ]] && kill -9 "$sim_pid" 2>/dev/null
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

fail() {
  failures=$((failures + 1))
  printf 'FAIL %s\n' "$*"
}

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
