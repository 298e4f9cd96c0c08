#!/usr/bin/env bash
# Runs the real `hmc` binary as a user would and checks its output and exit codes.
# Usage: cli_test.sh HMC_BINARY SOURCE_DIR
set -uo pipefail
hmc=$(realpath "$1")
src=$(realpath "$2")
# shellcheck source=sim_test_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/sim_test_lib.sh"

expect encode-words 0 '^STX#6#STM#1#1#128#1000#500#94#ETX$' -- "$hmc" frame encode STM 1 1 128 1000 500
expect encode-notation 0 '^STX#3#SVM#1#135#136#ETX$' -- "$hmc" frame encode '[#SVM#1#135]'
expect encode-lowercase-name 0 '^STX#6#LED#1#200#120#100#20#185#ETX$' -- "$hmc" frame encode led 1 200 120 100 20
expect encode-bad-microstep 1 'microstep is 3: expected a power of two 1-256' -- "$hmc" frame encode STM 1 1 3 1000 500
expect encode-home-motor-3 1 'no_switch' -- "$hmc" frame encode STM 3 3 0 0 0
expect encode-too-few 1 'SVM takes 2 values \(SVM <servo> <angle>\), got 1' -- "$hmc" frame encode SVM 1
expect encode-warns 0 'warning: delay_us 20 is outside' -- "$hmc" frame encode STM 3 1 8 0 20
check encode-stdout-clean 'STX#6#STM#3#1#8#0#20#32#ETX' "$("$hmc" frame encode STM 3 1 8 0 20 2>/dev/null)"
expect encode-json 0 '"frame":"STX#3#SVM#2#90#92#ETX"' -- "$hmc" frame encode SVM 2 90 --json

expect encode-ver 0 '^STX#1#VER#0#ETX$' -- "$hmc" frame encode VER
expect encode-set 0 '^STX#4#SET#1#3#8000#68#ETX$' -- "$hmc" frame encode SET 1 3 8000
expect encode-set-range 1 'value is 5000: expected 100-4000 for setting 1 \(current_ma\)' -- "$hmc" frame encode SET 1 1 5000
expect encode-crc 0 '^STX#6#STM#1#1#128#1000#500#20499#ETX$' -- "$hmc" frame encode --crc STM 1 1 128 1000 500
expect encode-crc-padded 0 '^STX#1#VER#04369#ETX$' -- "$hmc" frame encode --crc VER
expect encode-ver-notation 0 '^STX#1#VER#0#ETX$' -- "$hmc" frame encode '[#VER]'

expect decode-ok 0 'stepper 1 forward 1000 steps at 1/128 step, 500 us per step' -- "$hmc" frame decode 'STX#6#STM#1#1#128#1000#500#94#ETX'
expect decode-example-5 1 'checksum is 238 where 248 was expected' -- "$hmc" frame decode 'STX#6#STM#3#1#1#11#1000#238#ETX'
expect decode-caret 1 '^ {26}\^ byte 24, field .checksum.' -- "$hmc" frame decode 'STX#6#STM#3#1#1#11#1000#238#ETX'
expect decode-json 1 '"reason":"checksum_mismatch".*' -- "$hmc" frame decode --json 'STX#6#STM#3#1#1#11#1000#238#ETX'
expect decode-notation-hint 1 'command-set notation' -- "$hmc" frame decode '[#STM#1#1#128#1000#500]'
expect decode-canonical 0 'canonical form: STX#3#SVM#1#10#11#ETX' -- "$hmc" frame decode ' STX#03#SVM#1#10#11#ETX'
expect decode-crc 0 'checksum=20499' -- "$hmc" frame decode --crc 'STX#6#STM#1#1#128#1000#500#20499#ETX'
expect decode-crc-seed-sum 1 "this is the seed's sum" -- "$hmc" frame decode --crc 'STX#6#STM#1#1#128#1000#500#94#ETX'
expect decode-crc-width 1 'in CRC-16 mode the checksum is exactly 5 digits' -- "$hmc" frame decode --crc 'STX#1#VER#4369#ETX'
expect decode-crc-padded 0 'checksum=4369' -- "$hmc" frame decode --crc 'STX#1#VER#04369#ETX'
expect decode-board-nak 0 'NAK \(reply\): refused: checksum_mismatch at token 8, byte 24' -- "$hmc" frame decode --board 'STX#4#NAK#8#8#24#40#ETX'
expect decode-board-event 0 'EVD \(event\): motor 1 stopped at -1600' -- "$hmc" frame decode --board 'STX#5#EVD#1#2#1#1600#68#ETX'
expect decode-board-json 0 '"position":-1600' -- "$hmc" frame decode --board --json 'STX#5#EVD#1#2#1#1600#68#ETX'
expect decode-board-command 1 'STM is one of the commands' -- "$hmc" frame decode --board 'STX#6#STM#1#1#128#1000#500#94#ETX'
expect decode-empty 1 'no frame on the line' -- "$hmc" frame decode ''

expect check-spec 1 'spec-frames.txt:14: error: checksum_mismatch' -- "$hmc" frame check "$src/examples/spec-frames.txt"
expect check-spec-count 1 '28 frames: 27 valid, 1 invalid' -- "$hmc" frame check "$src/examples/spec-frames.txt"
expect check-example 0 '11 frames: 11 valid, 0 invalid' -- "$hmc" frame check "$src/examples/pan-tilt-and-lights.txt"
expect check-stdin 1 '^-:2: error: unknown_command' -- bash -c "printf 'STX#3#SVM#1#10#11#ETX\r\nSTX#3#SVX#1#10#11#ETX\n' | '$hmc' frame check -q -"
expect check-json 0 '"line":1' -- bash -c "echo 'STX#3#SVM#1#10#11#ETX' | '$hmc' frame check --json -"
expect check-board 1 '3 frames: 2 valid, 1 invalid' -- bash -c "printf 'STX#1#ACK#0#ETX\nSTX#2#EVE#1#1#ETX\nSTX#1#ACK#1#ETX\n' | '$hmc' frame check --board -"
expect check-missing-file 3 "cannot read '/nonexistent'" -- "$hmc" frame check /nonexistent

expect version 0 '^hmc [0-9]+\.[0-9]+\.[0-9]+' -- "$hmc" --version
expect help 0 'Examples:' -- "$hmc" --help
expect usage-error 2 'frame is required' -- "$hmc" frame decode
expect unknown-subcommand 2 '.' -- "$hmc" frobnicate

echo "$((checks - failures)) passed, $failures failed"
[[ $failures -eq 0 ]]
