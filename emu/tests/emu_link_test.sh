#!/usr/bin/env bash
# hmc against the real firmware image on hmc-emu, end to end (issue 17): through emu:// (hmc
# starts hmc-emu itself) a ramped move waited for gives hmc-sim's result and status reads as
# hmc-sim's, homing finds a switch placed with axis=; through hmc-emu --tcp with --control, an
# emergency press on the control channel ends a waited move (hmc reports it, exit 5) and the
# motors stop, a driver fault is reported, and `hmc servo`/`hmc led` reach the devices on the pins
# (the trace: the servo's pulse, the strip's colour decoded from its bitstream); the emergency
# press again through emu://'s own control=; the trace= option; every hmc-emu that hmc started ends with it, also when hmc is killed.
# hmc-sim's board is sim:// here: the same board as the hmc-sim program's, in hmc's process.
# Usage: emu_link_test.sh HMC_EMU HMC IMAGE_DIR [quick]
#   quick (the sanitizer presets): only the move, the kill and the port errors.
# Without the image the test is skipped (exit 77), unless CI is set: then it fails.
set -uo pipefail
emu_real=$(realpath "$1")
hmc=$(realpath "$2")
image=$(realpath -m "$3")/hmc-firmware.elf
quick=${4:-}
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$image"

# hmc finds hmc-emu through HMC_EMU: a wrapper that notes each started hmc-emu's process id, so
# the test can check that none outlives its hmc.
cat >"$work/hmc-emu" <<EOF
#!/bin/sh
echo \$\$ >>"$work/emu.pids"
exec "$emu_real" "\$@"
EOF
chmod +x "$work/hmc-emu"
export HMC_EMU=$work/hmc-emu
: >"$work/emu.pids"

# alive PID: the process exists and is not a zombie.
alive() {
  local state
  state=$(ps -o stat= -p "$1" 2>/dev/null) || return 1
  [[ -n $state && $state != Z* ]]
}

# Every hmc-emu started so far has ended (within 2 s of its hmc).
none_left() {
  local pid left=
  for _ in $(seq 40); do
    left=
    while read -r pid; do alive "$pid" && left+=" $pid"; done <"$work/emu.pids"
    [[ -z $left ]] && break
    sleep 0.05
  done
  check "$1: no hmc-emu left running" "" "$left"
}

t0=$(ms)
# The emulator may run slower than real time on a loaded machine: generous reply timeouts.
emu_port="emu://$image?fast"
sim_port="sim://link?fresh&fast"

# 1. A ramped move, waited for: the same report as hmc-sim's (both boards start with motor 1 at
# 0 and idle: emu:// lets the image's power-up self-test finish first).
# The board's trace (trace=) shows the steps on the STEP pin: with the axis starting at 102400
# (1/256 step), the last at 102400 + 3200 × 16.
emu_out=$("$hmc" --port "$emu_port&axis=1:0:409600:102400&trace=$work/move.trace" --timeout 5000 \
  move 1 3200 --accel 8000 --wait 2>"$work/move.err")
emu_code=$?
check "move --wait: trace= gives the STEP pin's last position" '"pos":153600}' \
  "$(grep '"ev":"step","motor":1,' "$work/move.trace" | tail -n 1 | grep -o '"pos":[-0-9]*}')"
sim_out=$("$hmc" --port "$sim_port" move 1 3200 --accel 8000 --wait 2>/dev/null)
sim_code=$?
check "move --wait: exit code as hmc-sim's" "$sim_code" "$emu_code"
check "move --wait: report as hmc-sim's" "$sim_out" "$emu_out"
check_match "move --wait: the report" '^motor 1: done, at 3200 steps of 1/16' "$emu_out"
check_match "move --wait: the board is the emulated one" "^board: emulated board emu://.*hmc-firmware.elf, fast" \
  "$(cat "$work/move.err")"
none_left "move --wait"

# 2. hmc killed (SIGKILL: no chance to close anything) while it holds an emu:// board: its
# hmc-emu ends too (PR_SET_PDEATHSIG; the pseudo-terminal's hang-up would end it as well).
"$hmc" --port "$emu_port" --timeout 5000 monitor >"$work/monitor.out" 2>&1 &
hmc_pid=$!
pids+=("$hmc_pid")
for _ in $(seq 300); do
  grep -q 'listening until Ctrl-C' "$work/monitor.out" 2>/dev/null && break
  sleep 0.05
done
child=$(pgrep -P "$hmc_pid" | head -1)
check "monitor: hmc-emu started" "yes" "$([[ -n $child ]] && alive "$child" && echo yes)"
{
  kill -9 "$hmc_pid"
  wait "$hmc_pid"
} 2>/dev/null
none_left "hmc killed"

# 3. Port errors: a clear message, exit 3 (a port that cannot be used), no hmc-emu started.
expect missing-image 3 "no firmware image 'nowhere.elf'" -- "$hmc" --port "emu://nowhere.elf" status
expect bad-option 3 "unknown option 'bogus'" -- "$hmc" --port "emu://$image?bogus" status
expect bad-axis 3 "hmc-emu ended \\(exit status 2\\)" -- "$hmc" --port "emu://$image?axis=3:0:1:0" status
expect no-emulator 3 "HMC_EMU is '/nonexistent'" -- env HMC_EMU=/nonexistent "$hmc" --port "emu://$image" status
none_left "port errors"

if [[ $quick != quick ]]; then
  # 4. status of a board just booted reads as hmc-sim's, but for the servos: the image's boot
  # pulse train (500 ms after its last SVM) has stopped by the time emu:// lets the host in.
  # Installed as the packages install them: hmc and hmc-emu in bin, the hmc-firmware package's
  # raw image in share/hmc/firmware; hmc finds both itself.
  mkdir -p "$work/usr/bin" "$work/usr/share/hmc/firmware"
  cp "$hmc" "$work/usr/bin/hmc"
  cp "$work/hmc-emu" "$work/usr/bin/hmc-emu"
  cp "$(dirname "$image")/hmc-firmware.bin" "$work/usr/share/hmc/firmware/"
  emu_out=$(env -u HMC_EMU "$work/usr/bin/hmc" --port "emu://?fast" --timeout 5000 status 2>"$work/status.err")
  check_match "status: the installed image" "^board: emulated board emu://\\?fast \\(hmc-emu $work/usr/share/hmc/firmware/hmc-firmware.bin," \
    "$(cat "$work/status.err")"
  check_match "status: servos released" '^servo 1 \(pan\): released +servo 2 \(tilt\): released$' "$emu_out"
  sim_out=$("$hmc" --port "$sim_port" status 2>/dev/null)
  check "status: as hmc-sim's (servo line aside)" "$(grep -v '^servo ' <<<"$sim_out")" "$(grep -v '^servo ' <<<"$emu_out")"

  # 5. Homing against the reverse switch, placed 50 full steps behind the start (axis=).
  expect home-1 0 '^motor 1: homed, at 0 steps of 1/16' -- \
    env HMC_EMU_FIRMWARE="$image" "$hmc" --port "emu://?fast&axis=1:0:409600:12800" --timeout 5000 home 1
  none_left "home"

  # 6. A board that stays up (hmc-emu --tcp) with the control channel: the emergency switch
  # pressed while hmc waits for a long move.
  "$emu_real" "$image" --fast --quiet --tcp 127.0.0.1:0 --control 127.0.0.1:0 --hold-input 1 \
    --trace "$work/board.trace" 2>"$work/board.err" &
  pid=$!
  pids+=("$pid")
  tcp=$(announced board 's/^hmc-emu: listening on \(tcp:\/\/127\.0\.0\.1:[0-9]*\)$/\1/p')
  control=$(announced board 's/^hmc-emu: control listening on tcp:\/\/127\.0\.0\.1:\([0-9]*\)$/\1/p')
  [[ -n $tcp && -n $control ]] || { fail "hmc-emu --tcp --control did not start"; finish emu_link_test; }
  exec 3<>"/dev/tcp/127.0.0.1/$control"
  # control COMMAND: one line to the control channel, its answer into $answer.
  control() {
    printf '%s\n' "$1" >&3
    IFS= read -r -t 10 answer <&3 || answer="(no answer)"
  }
  steps() { control status; sed -n 's/.*"motor":1,"pos":-\{0,1\}[0-9]*,"steps":\([0-9]*\).*/\1/p' <<<"$answer"; }
  # moving NAME: waits (20 s at most) until motor 1 has made 100 more STEP edges than when the
  # board's description showed on hmc's output $work/NAME (its VER answered: the self-test is
  # over and hmc's move is on its way).
  moving() {
    local before now=0
    for _ in $(seq 400); do
      grep -q '^board: ' "$work/$1" 2>/dev/null && break
      sleep 0.05
    done
    before=$(steps)
    for _ in $(seq 400); do
      now=$(steps)
      ((now > before + 100)) && break
      sleep 0.05
    done
    check "$1: motor 1 steps before the press" "yes" "$( ((now > before + 100)) && echo yes)"
  }
  # A long reply timeout: hmc-emu holds its VER until the self-test is over (slow under the
  # sanitizers).
  "$hmc" --port "$tcp" --timeout 30000 move 1 100000 --wait >"$work/estop.out" 2>&1 &
  move_pid=$!
  pids+=("$move_pid")
  moving estop.out
  control estop
  check "estop: control answer" "ok" "$answer"
  await_exit "$move_pid" 20
  check "estop: hmc's exit code (a motion ended early)" 5 "$finished"
  check_match "estop: hmc reports the emergency" '^motor 1: ended early: emergency, at [0-9]+ steps' \
    "$(cat "$work/estop.out")"
  first=$(steps)
  sleep 0.3
  check "estop: motor 1 stopped (STEP edges on the driver)" "$first" "$(steps)"
  control status
  check_match "estop: control status" '"emergency":true' "$answer"
  out=$("$hmc" --port "$tcp" --timeout 5000 status 2>&1)
  check_match "estop: status" '^emergency switch: PRESSED$' "$out"
  check_match "estop: status, motor 1 idle" '^1 +idle ' "$out"
  # A driver fault (DRV8711 STATUS bit 1, overcurrent on bridge A) is reported by the firmware.
  "$hmc" --port "$tcp" --timeout 5000 monitor >"$work/fault.out" 2>&1 &
  monitor_pid=$!
  pids+=("$monitor_pid")
  for _ in $(seq 200); do
    grep -q 'listening until Ctrl-C' "$work/fault.out" 2>/dev/null && break
    sleep 0.05
  done
  control "fault 2 2"
  check "fault: control answer" "ok" "$answer"
  for _ in $(seq 100); do
    grep -q 'EVF' "$work/fault.out" 2>/dev/null && break
    sleep 0.05
  done
  check_match "fault: hmc monitor shows the board's report" 'EVF event: motor 2 driver fault: AOCP \(STATUS 0x02\)' \
    "$(cat "$work/fault.out")"
  kill -INT "$monitor_pid"
  await_exit "$monitor_pid" 10
  control "press 3 0"
  check "control: a refused command" "error: motor '3': only motors 1 and 2 have limit switches" "$answer"
  # A servo and a strip, as the devices on the image's pins see them (the trace, written out when
  # hmc-emu ends): servo 1's last pulse before its release, for 135 degrees 544 + 135 × 1856 / 180
  # µs rounded (servo_pwm.h), and strip 2's colour as the bitstream carries it, each value scaled by the board's brightness
  # 100 of 255: v × 101 >> 8 (board.h kLedBrightness, sk6812.h scale()).
  control "estop release"
  check "estop release: control answer" "ok" "$answer"
  out=$("$hmc" --port "$tcp" --timeout 5000 servo 1 135 2>&1)
  check_match "servo: hmc's report" '^servo 1 \(pan\) to 135 degrees$' "$out"
  out=$("$hmc" --port "$tcp" --timeout 5000 led 2 '#102030ff' 2>&1)
  check_match "led: hmc's report" '^LED strip 2 to R16 G32 B48 W255$' "$out"
  sleep 0.3  # virtual time runs unthrottled (--fast): far more than a servo period and a latch
  exec 3>&-
  kill -TERM "$pid"
  await_exit "$pid" 10
  check "hmc-emu --tcp: exit code after SIGTERM" 0 "$finished"
  check "servo: the pulse on servo 1's pin" '"pulse_us":1936}' \
    "$(grep '"ev":"servo","servo":1,' "$work/board.trace" | grep -v released | tail -n 1 | grep -o '"pulse_us":[0-9]*}')"
  check "led: strip 2's colour decoded from its bitstream" '"r":6,"g":12,"b":18,"w":100}' \
    "$(grep '"ev":"led","strip":2,' "$work/board.trace" | tail -n 1 | grep -o '"r":.*}')"

  # 7. The same through emu://'s own control channel (control=): hmc-emu prints its address on
  # hmc's standard error before the board answers.
  "$hmc" --port "emu://$image?fast&control=127.0.0.1:0" --timeout 5000 move 1 100000 --wait >"$work/emu-estop.out" \
    2>"$work/emu-estop.err" &
  move_pid=$!
  pids+=("$move_pid")
  control=
  for _ in $(seq 400); do
    control=$(sed -n 's/^hmc-emu: control listening on tcp:\/\/127\.0\.0\.1:\([0-9]*\)$/\1/p' "$work/emu-estop.err" 2>/dev/null)
    [[ -n $control ]] && break
    sleep 0.05
  done
  if [[ -z $control ]]; then
    fail "emu:// with control=: no control address: $(cat "$work/emu-estop.err")"
  else
    exec 3<>"/dev/tcp/127.0.0.1/$control"
    moving emu-estop.err
    control estop
    check "emu:// estop: control answer" "ok" "$answer"
    exec 3>&-
    await_exit "$move_pid" 20
    check "emu:// estop: hmc's exit code" 5 "$finished"
    check_match "emu:// estop: hmc reports the emergency" '^motor 1: ended early: emergency, at [0-9]+ steps' \
      "$(cat "$work/emu-estop.out")"
  fi
fi

none_left "the end"
finish emu_link_test "$checks checks, $((($(ms) - t0) / 1000)) s"
