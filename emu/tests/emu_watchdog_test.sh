#!/usr/bin/env bash
# The main loop stalled → the watchdog resets the chip → the image boots again and its boot
# event (EVR) and STA 8 say the watchdog reset it (issue 17: "the main loop stalled → watchdog
# reset → the boot event reports it"). hmc-emu --stall-at hangs the CPU (no instruction, no
# interrupt) while the clocks and the watchdog run on; --watchdog-resets lets the expiry reset
# the chip (PM RCAUSE.WDT) instead of stopping the emulator.
# Usage: emu_watchdog_test.sh HMC_EMU IMAGE_DIR
# Without the image the test is skipped (exit 77), unless CI is set: then it fails.
set -uo pipefail
emu=$(realpath "$1")
image=$(realpath -m "$2")/hmc-firmware.elf
# shellcheck source=SCRIPTDIR/../../cli/sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/../../cli/sim_test_lib.sh"
require_built "$image"

# Each run's script ends at 1.3 s, well past the stall plus the watchdog's period (the chip
# resets about 0.5 s after the stall); with standard input empty the run ends 200 ms later.
printf 'at 1300ms send STX#2#STA#8#8#ETX\n' >"$work/script"
out=$(timeout 120 "$emu" "$image" --fast --quiet --watchdog-resets --stall-at 0.5 --max-time 10 \
        --script "$work/script" 2>"$work/err" </dev/null)
check "stalled: exit 0" 0 $?
check "stalled: booted twice, the second time reset by the watchdog (EVR and STR cause 4)" \
  "STX#3#EVB#7#100#107#ETX
STX#6#EVR#1#0#0#0#0#1#ETX
STX#3#EVB#7#100#107#ETX
STX#6#EVR#4#0#0#0#0#4#ETX
STX#6#STR#4#0#0#0#0#4#ETX" "$out"

# Without --watchdog-resets the expiry stops the emulator as an error.
timeout 120 "$emu" "$image" --fast --quiet --stall-at 0.5 --max-time 10 --script "$work/script" \
  >/dev/null 2>"$work/err" </dev/null
check "stalled, no resets: exit 5" 5 $?
check "stalled, no resets: the message" 1 "$(grep -c 'watchdog expired: the main loop stopped kicking it' "$work/err")"

# Not stalled: the main loop kicks the watchdog; one boot, power-on.
out=$(timeout 120 "$emu" "$image" --fast --quiet --watchdog-resets --max-time 10 \
        --script "$work/script" 2>/dev/null </dev/null)
check "running: one boot, power-on" "STX#3#EVB#7#100#107#ETX
STX#6#EVR#1#0#0#0#0#1#ETX
STX#6#STR#1#0#0#0#0#1#ETX" "$out"

[[ $failures -eq 0 ]]
