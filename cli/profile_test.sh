#!/usr/bin/env bash
# The machine profile through the real `hmc` binary: `hmc config path | show | check` on the
# example profiles and on a profile with mistakes (every one with line:column, nothing sent),
# then axes by name and units on the simulated board (sim://, in the hmc process).
# Usage: profile_test.sh HMC_BINARY SOURCE_DIR
set -uo pipefail
if [[ $# -ne 2 || ! -x $1 || ! -d $2 ]]; then
  echo "usage: $0 HMC_BINARY SOURCE_DIR" >&2
  exit 2
fi
hmc=$(realpath "$1")
src=$(realpath "$2")
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"
export XDG_CONFIG_HOME=$work/config
unset HMC_PROFILE

# --- hmc config ---------------------------------------------------------------------------------
expect path-default 0 "^$work/config/hmc/config.toml$" -- "$hmc" config path
expect path-default-missing 0 'the default; it does not exist' -- "$hmc" config path
expect path-env 0 '"from":"HMC_PROFILE"' -- env HMC_PROFILE=/x.toml "$hmc" config path --json
expect path-option 0 '^/y.toml$' -- env HMC_PROFILE=/x.toml "$hmc" --profile /y.toml config path
expect show-none 3 'no profile: .*config.toml does not exist' -- "$hmc" config show
for f in "$src"/examples/*.toml; do
  expect "check-$(basename "$f")" 0 ': valid: [0-9]+ ax' -- "$hmc" config check "$f"
done
expect show-slider 0 'axis slide \(motor 1\): linear, 40 mm per turn; 200 steps per turn at 1/16 = 80 steps per mm' \
  -- "$hmc" --profile "$src/examples/camera-slider.toml" config show
expect show-pan-gear 0 'gear 3:1 = 26.6667 steps per deg' -- "$hmc" --profile "$src/examples/pan-tilt-head.toml" config show
expect show-json 0 '"steps_per_unit": 80' -- "$hmc" --profile "$src/examples/camera-slider.toml" config show --json
mkdir -p "$work/config/hmc"
cp "$src/examples/gantry.toml" "$work/config/hmc/config.toml"
expect check-default 0 'config.toml: valid: 3 axes \(x, y, z\)' -- "$hmc" config check

cat >"$work/bad.toml" <<'TOML'
baud = "fast"

[axis.slide]
motor = 1
pulley_teeth = 20
belt_pitch = "2mm"
spead = "20mm/s"
limits = ["300mm", "0mm"]

[axis.pan]
motor = 1
rotary = true
limits = ["0mm", "90deg"]
TOML
out=$("$hmc" config check "$work/bad.toml" 2>&1)
code=$?
checks=$((checks + 1))
[[ $code == 1 ]] || { failures=$((failures + 1)); echo "FAIL bad profile: exit $code, want 1"; }
for want in 'bad.toml:1:8: baud must be a whole number, not a string' \
            "bad.toml:7:1: unknown key 'spead' in axis 'slide'" \
            "bad.toml:8:10: axis 'slide' limits are the wrong way round" \
            "bad.toml:11:9: motor 1 is named twice: by axis 'slide' \\(line 4\\) and by axis 'pan'" \
            "bad.toml:13:11: axis 'pan' limits low: axis 'pan' is rotary: it takes deg, rev or steps, not mm" \
            '^5 errors in the profile; nothing was sent$'; do
  checks=$((checks + 1))
  grep -Eq -- "$want" <<<"$out" || { failures=$((failures + 1)); printf 'FAIL bad profile lacks %s:\n%s\n' "$want" "$out"; }
done
printf 'baud = 1\n[axis.a\nmotor = 1\ncolour = 2\n' >"$work/syntax.toml"
expect syntax-place 1 'syntax.toml:2:8: TOML syntax' -- "$hmc" config check "$work/syntax.toml"
expect syntax-alone 1 '^1 error in the profile \(a syntax error hides any after it\)' -- "$hmc" config check "$work/syntax.toml"
expect json-errors 1 '"line":1,"message":"baud must be a whole number' -- "$hmc" config check "$work/bad.toml" --json
# A profile with mistakes sends nothing: not even VER.
expect bad-profile-no-board 1 'nothing was sent' -- "$hmc" --profile "$work/bad.toml" --port sim://never status
[[ -e $work/state/sim-never.journal ]] && { failures=$((failures + 1)); echo "FAIL a bad profile opened the board"; }

# --- axes by name, in their units, on the simulated board ----------------------------------------
slider=(--profile "$src/examples/camera-slider.toml")
expect home-slide 0 'motor 1: homed, at 0 steps' -- "$hmc" "${slider[@]}" --port 'sim://s?fresh&fast' home slide
expect move-to-250mm 0 '^slide at 250 mm \(20000 steps of 1/16\), 0 mm/s, homed$' \
  -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --to 250mm --speed 200mm/s --accel 1000mm/s2 --wait
expect status-mm 0 '^  slide at 250 mm \(20000 steps of 1/16\), 0 mm/s, homed$' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' status
expect status-steps 0 '^1 +idle +20000 +20000 +1/16 ' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' status
expect status-json 0 '"axis": "slide",' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' status --json
expect status-json-mm 0 '"position": 250.0,' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' status --json
expect wrong-unit 2 "error: --to: axis 'slide' is linear: it takes mm, rev or steps, not deg" \
  -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --to 90deg
expect speed-as-position 2 "'mm/s' is a speed, but a position or distance is wanted here \(mm\)" \
  -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --by 20mm/s
expect soft-limit 1 "axis 'slide': 400 mm is beyond its soft limits, 0 to 310 mm" \
  -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --to 400mm
expect rounded 0 "note: --by -0.01mm on axis 'slide' is -0.8 steps: rounded to -1" \
  -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --by -0.01mm --wait
expect by-rev 0 '^slide at 209.988 mm \(16799 steps of 1/16\)' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --by=-1rev --wait
expect to-steps 0 '^slide at 250 mm \(20000 steps' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --to 20000steps --wait
expect already-there 0 'already there' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide --to 250mm
expect stop-by-name 0 'motor 1: stopped' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' stop slide
expect unknown-axis 2 "no axis 'pan': give a motor 1-3 or an axis name; the profile's axes are slide \(1\)" \
  -- "$hmc" "${slider[@]}" --port sim://nowhere move pan --to 1deg
[[ -e $work/state/sim-nowhere.journal ]] && { failures=$((failures + 1)); echo "FAIL an unknown axis opened the board"; }
expect to-with-steps 2 '--to and --by take the axis' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' move slide 100 --to 1mm

# Rotary axes, an inverted one, and a motor no profile axis drives (degrees at 200 steps per turn).
pan_tilt=(--profile "$src/examples/pan-tilt-head.toml" --port 'sim://p?fresh&fast')
expect pan-by 0 '^pan at -90 deg \(-2400 steps of 1/16\)' -- "$hmc" "${pan_tilt[@]}" move pan --by -90deg --wait
expect tilt-inverted 0 '^motor 2: done, at -3200 steps' -- "$hmc" "${pan_tilt[@]}" move tilt --to 180deg --wait
expect pan-mm 2 "axis 'pan' is rotary: it takes deg, rev or steps, not mm" -- "$hmc" "${pan_tilt[@]}" move pan --to 10mm
expect motor-3-deg 0 '^motor 3 at 90 deg \(800 steps of 1/16\)' -- "$hmc" "${pan_tilt[@]}" move 3 --to 90deg --wait
expect accel-number 0 'motor 1: done' -- "$hmc" "${pan_tilt[@]}" move 1 3200 --accel 8000 --wait

# Zero: POS (protocol 6) on motor 3, which has no switches; then the profile's limits are on the board.
# (the default profile is the gantry's by now: motor 3 is its axis z)
expect zero-3 0 '^z at 0 mm \(0 steps of 1/16\), 0 mm/s, homed$' -- "$hmc" --port 'sim://s?fast' zero 3
expect zero-3-status 0 '^3 +idle +0 +0 +1/16 +0 +yes' -- "$hmc" --port 'sim://s?fast' status
expect zero-value 0 '^slide at 100 mm \(8000 steps of 1/16\)' -- "$hmc" "${slider[@]}" --port 'sim://s?fast' zero slide 100mm
expect zero-wrong-unit 2 "axis 'slide' is linear: it takes mm, rev or steps, not deg" -- "$hmc" "${slider[@]}" --port 'sim://s?fast' zero slide 5deg
expect zero-seed 1 "the board's firmware is too old for this: reflash" -- "$hmc" --port 'sim://old?fast&seed' --firmware seed zero 3
# The board enforces the limits it was sent: 0-310 mm is now -100 mm to 210 mm of the board's old count.
expect board-soft-limit 1 'soft' -- "$hmc" --port 'sim://s?fast' move 1 24000 --microstep 16

# The profile's port, baud and firmware when the command line gives none.
printf 'port = "sim://fromprofile?fast"\nbaud = 57600\n[axis.a]\nmotor = 1\nrotary = true\n' >"$work/port.toml"
expect port-from-profile 0 'board: simulated board sim://fromprofile' -- "$hmc" --profile "$work/port.toml" status
expect port-option-wins 0 'board: simulated board sim://other' -- "$hmc" --profile "$work/port.toml" --port 'sim://other?fast' status

# --- motion files and the profile hmc uses -------------------------------------------------------
# (the default profile is still the gantry's)
printf '{"hmc_motion": 1, "steps": [{"move": {"motor": "slide", "by": {"mm": 10}}}]}\n' >"$work/bare.json"
expect file-takes-profile 0 'bare.json: valid: 1 steps' -- "$hmc" "${slider[@]}" check "$work/bare.json"
expect file-takes-default 1 "unknown motor 'slide' .*x, y, z" -- "$hmc" check "$work/bare.json"
expect file-other-profile 1 "\\\$.profile: the file was written for the profile .*/camera-slider.toml, not for .*/pan-tilt-head.toml, which --profile chooses: give --profile the file's profile, or none" \
  -- "$hmc" --profile "$src/examples/pan-tilt-head.toml" check "$src/examples/camera-slider-mm.json"
expect file-other-env 1 'which HMC_PROFILE chooses' \
  -- env HMC_PROFILE="$src/examples/pan-tilt-head.toml" "$hmc" check "$src/examples/camera-slider-mm.json"
expect file-same-profile 0 'camera-slider-mm.json: valid' -- "$hmc" "${slider[@]}" check "$src/examples/camera-slider-mm.json"
expect file-over-default 0 "note: .*\\\$.profile: the file's profile .*/camera-slider.toml is used, not the default .*/config.toml" \
  -- "$hmc" check "$src/examples/camera-slider-mm.json"

# A motion file's home applies the profile's homing, as `hmc home` does: pulled 2 mm off the
# switch without a slow re-approach, the motor rests at 2 mm, and `to 10mm` counts from there.
sed 's/^seek_speed = .*/&\npull_off = "2mm"/' "$src/examples/camera-slider.toml" >"$work/pull-off.toml"
printf '{"hmc_motion": 1, "steps": [{"home": "slide"}]}\n' >"$work/home.json"
printf '{"hmc_motion": 1, "steps": [{"home": "slide"}, {"move": {"motor": "slide", "to": {"mm": 10}}}]}\n' >"$work/home-to.json"
pull_off=(--profile "$work/pull-off.toml" --port 'sim://h?fresh&fast')
expect home-pull-off 0 '^motor 1: homed, at 160 steps of 1/16' -- "$hmc" "${pull_off[@]}" home slide
expect file-home-pull-off 0 '^done: 1 steps; slide at 160 steps of 1/16' -- "$hmc" "${pull_off[@]}" run "$work/home.json"
expect file-home-then-to 0 '^done: 2 steps; slide at 800 steps of 1/16' -- "$hmc" "${pull_off[@]}" run "$work/home-to.json"
# The frames: the settings first (end, pull-off 160 steps, no re-approach), the seek at 20 mm/s,
# then the soft limits (0-310 mm in 1/256 steps).
for frame in 'SET#1#5#0#' 'SET#1#7#160#' 'SET#1#8#0#' 'STM#1#3#16#0#625#' 'LIM#1#0#0#0#396800#'; do
  expect "file-home-frame-$frame" 0 "\\[1\\] +STX#[0-9]+#$frame" -- "$hmc" "${pull_off[@]}" run "$work/home.json" --dry-run
done

if ((failures > 0)); then
  echo "profile_test: $failures of $checks checks failed"
  exit 1
fi
echo "profile_test: all $checks checks passed"
