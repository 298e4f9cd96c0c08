#!/usr/bin/python3
"""Replays the behaviour vectors (conformance/vectors/behaviour_*.json) against the firmware
image on hmc-emu: each vector's sends, switch presses and emergency stops are injected at their
virtual times (hmc-emu --script), and every reply and event the vector expects must come, in
order, over the emulated UART.

What differs from behaviour_test (the host-built core on the simulated board), and why:
  - The image always runs its power-up self-test; the vectors assume a board without it
    (unless their board says "self_test": true). Those vectors start at START_MS, after the
    self-test has ended with every motor back where it started, and after a VER whose answer
    marks the start: of what came before, only the boot events (EVB, EVR) count as the
    vector's; the self-test's own switch changes, which it undoes (an axis starting on a switch
    leaves it and comes back, one near a switch runs onto it and back: two EVL), do not.
  - Only what the wire shows is checked: `replies` and `events`. Step counts, positions, axes,
    servo pulses, LED colours, tones and states are the emulated board's devices, not
    compared here (the replies and events carry the positions and states the firmware reports).
  - The image is built in normal mode: `legacy` and `seed` modes are not played.
  - A vector's axes become hmc-emu --axis options; its accelerations are set by SET lines
    100 ms before it starts (their ACKs are set aside). Driver faults (`fault`: DRV8711 STATUS
    bits) and a switch put back to its axis position (`auto`) are injected as hmc-sim does.
  - The image receives at 115200 baud, as the sim with "baud" set; lines take their wire time,
    so the fields uart_differences.json lists (a running motor's STA position, target, rate)
    are not compared, as in conformance_over_uart.py.

Usage: behaviour_over_uart.py VECTORS_DIR HMC_EMU IMAGE [ID...]   (IDs: only those vectors)
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile

from conformance_over_uart import comparable, differences

START_MS = 1000  # the self-test ends before 900 ms of virtual time
SETTLE_MS = 300  # after the last step, for the last replies and events
LONGEST_MS = 5000  # longer vectors are not played: seconds of emulation each


def playable(vector):
    """None, or why the vector cannot be played against the image."""
    if "normal" not in vector.get("modes", ["normal", "legacy"]):
        return "not in normal mode"
    board = {k: v for k, v in vector.get("board", {}).items()
             if k not in ("baud", "self_test", "axes", "accel")}
    if board:
        return "changes the simulated board: " + ", ".join(sorted(board))
    if max(step["at_ms"] for step in vector["script"]) > LONGEST_MS:
        return f"longer than {LONGEST_MS} ms of virtual time (the CI share)"
    for step in vector["script"]:
        for key in step:
            if key not in ("at_ms", "send", "press", "release", "auto", "estop", "fault", "expect",
                           "expect_legacy", "expect_seed"):
                return f"uses '{key}'"
    return None


def board_options(vector):
    """hmc-emu's --axis options for the vector's axes (hmc-sim's defaults for the rest)."""
    options = []
    for motor, axis in vector.get("board", {}).get("axes", {}).items():
        low, high, start = axis.get("low", 0), axis.get("high", 409600), axis.get("start", 204800)
        options += ["--axis", f"{motor}:{low}:{high}:{start}"]
    return options


def accel_lines(vector):
    """SET lines giving the motors the vector's accelerations (setting 3), each answered ACK."""
    lines = []
    for motor, accel in enumerate(vector.get("board", {}).get("accel", []), start=1):
        if accel:
            lines.append(f"STX#4#SET#{motor}#3#{accel}#{(motor + 3 + accel) % 256}#ETX")
    return lines


def boot_events(before):
    """The events sent before the vector starts that a board without the self-test sends too.
    The self-test leaves every axis where it started, so the switch changes it causes (leaving
    a switch the axis starts on, or running onto one near its start) are undone before it ends:
    a switch change followed by its undo is dropped, pair by pair, leaving each switch's net
    change since power-up (the press reported at boot of a switch the axis starts on)."""
    kept = []
    for line in (l for l in before if "#EV" in l):
        fields = line.split("#")
        if fields[2] == "EVL":
            same = [i for i, k in enumerate(kept) if k.split("#")[2:5] == fields[2:5]]
            if same and kept[same[-1]].split("#")[5] != fields[5]:
                del kept[same[-1]]
                continue
        kept.append(line)
    return kept


MARK = "STX#1#VER#0#ETX"  # sent last before a vector starts: its answer ends the prelude


def script(vector, start_ms):
    # The accelerations are set just before the vector starts (the self-test is over), then a
    # VER marks where the vector begins in what the board sends.
    lines = [f"at {start_ms - 100}ms send {line}" for line in accel_lines(vector)]
    if start_ms > 0:
        lines.append(f"at {start_ms - 50}ms send {MARK}")
    for step in vector["script"]:
        at = f"at {round((start_ms + step['at_ms']) * 1000)}us"
        if "send" in step:
            lines += [f"{at} send {line}" for line in step["send"].split("\n")]
        for key in ("press", "release", "auto", "fault"):
            if key in step:
                motor, end = step[key]  # fault: motor and STATUS bits
                lines.append(f"{at} {key} {motor} {end}")
        if "estop" in step:
            lines.append(f"{at} estop" + ("" if step["estop"] else " release"))
    return "\n".join(lines) + "\n"


def expected(vector, key):
    """Everything the vector expects under `key` (replies or events), and whether the last such
    expectation comes after the vector's last action (then nothing more may come)."""
    lines, last_expect, last_action = [], -1, -1
    for i, step in enumerate(vector["script"]):
        if any(k in step for k in ("send", "press", "release", "auto", "estop", "fault")):
            last_action = i
        if key in step.get("expect", {}):
            lines += step["expect"][key]
            last_expect = i
    return lines, last_expect >= 0, last_expect >= last_action


def main(directory, emu, image, *only):
    if not os.path.isfile(image):
        if os.environ.get("CI") == "true":
            print(f"FAIL: no firmware image {image} (build the firmware preset first)")
            return 1
        print(f"SKIP: no firmware image {image}")
        return 77
    masked = differences(pathlib.Path(__file__).with_name("uart_differences.json"), "behaviour")
    failures, played, skipped = 0, 0, []
    with tempfile.TemporaryDirectory() as work:
        for path in sorted(pathlib.Path(directory).glob("behaviour_*.json")):
            for vector in json.loads(path.read_text(encoding="utf-8"))["vectors"]:
                if only and vector["id"] not in only:
                    continue
                why = playable(vector)
                if why:
                    skipped.append(f"{vector['id']} ({why})")
                    continue
                self_test = vector.get("board", {}).get("self_test", False)
                start = 0 if self_test else START_MS
                script_path = pathlib.Path(work) / "script.txt"
                script_path.write_text(script(vector, start), encoding="latin-1")
                end_ms = start + max(s["at_ms"] for s in vector["script"]) + SETTLE_MS
                # Standard input stays open (a pipe nobody writes): the run lasts until
                # --max-time, so a late event is not cut off by the end of input.
                quiet_in, keep_open = os.pipe()
                run = subprocess.run(
                    [emu, image, "--fast", "--quiet", "--script", str(script_path),
                     "--max-time", str(end_ms / 1000)] + board_options(vector),
                    stdin=quiet_in, capture_output=True, timeout=300)
                os.close(quiet_in)
                os.close(keep_open)
                played += 1
                lines = run.stdout.decode("latin-1").splitlines()
                problems = []
                if start > 0:
                    # Before the vector: the boot events (the vector expects them), the
                    # self-test's own events (not the vector's), the SETs' ACKs and the VER.
                    ver = next((i for i, l in enumerate(lines) if "#VER#" in l), None)
                    if ver is None:
                        problems.append("the VER before the vector was not answered")
                        ver = len(lines) - 1
                    before, lines = lines[:ver + 1], lines[ver + 1:]
                    acks = [l for l in before if l == "STX#1#ACK#0#ETX"]
                    if len(acks) != len(accel_lines(vector)):
                        problems.append(f"the accelerations were not all taken: {before}")
                    lines = boot_events(before) + lines
                is_event = lambda l: l.split("#")[2:3] != [] and l.split("#")[2].startswith("EV")
                got = {"events": [l for l in lines if is_event(l)],
                       "replies": [l for l in lines if not is_event(l)]}
                if run.returncode != 6:  # the end at --max-time
                    problems.append(f"hmc-emu exit {run.returncode}: {run.stderr.decode().strip()}")
                for key in ("replies", "events"):
                    want, checked, whole = expected(vector, key)
                    if not checked:
                        continue
                    have = got[key] if whole else got[key][:len(want)]
                    if [comparable(l, masked) for l in have] != [comparable(l, masked) for l in want]:
                        problems.append(f"{key}:\n    want {want}\n    got  {got[key]}")
                if problems:
                    failures += 1
                    print(f"FAIL {vector['id']}: " + "\n  ".join(problems))
                else:
                    print(f"ok   {vector['id']}")
    for line in skipped:
        print(f"skip {line}")
    print(f"behaviour over the emulated UART: {played} vectors played, {len(skipped)} skipped, "
          f"{failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
