#!/usr/bin/python3
"""Replays the behaviour vectors (conformance/vectors/behaviour_*.json) against the firmware
image on hmc-emu: each vector's sends, switch presses and emergency stops are injected at their
virtual times (hmc-emu --script), and every reply and event the vector expects must come, in
order, over the emulated UART.

What differs from behaviour_test (the host-built core on the simulated board), and why:
  - The image always runs its power-up self-test; the vectors assume a board without it
    (unless their board says "self_test": true). Those vectors start at kStart, after the
    self-test has ended with every motor back at 0; the self-test's own lines come before.
  - Only what the wire shows is checked: `replies` and `events`. Step counts, positions, axes,
    servo pulses, LED colours, tones and states are the emulated board's devices, not
    compared here (the replies and events carry the positions and states the firmware reports).
  - The image is built in normal mode: `legacy` and `seed` modes are not played.
  - Vectors that change the simulated board (axes, accelerations), inject driver faults or put
    a switch back to its axis position (`auto`) are skipped and listed: hmc-emu has no option for
    them yet.
  - The image receives at 115200 baud, as the sim with "baud" set; lines take their wire time,
    so the fields uart_differences.json lists (a running motor's STA position, target, rate)
    are not compared, as in conformance_over_uart.py.

Usage: behaviour_over_uart.py VECTORS_DIR HMC_EMU IMAGE
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


def playable(vector):
    """None, or why the vector cannot be played against the image."""
    if "normal" not in vector.get("modes", ["normal", "legacy"]):
        return "not in normal mode"
    board = {k: v for k, v in vector.get("board", {}).items() if k not in ("baud", "self_test")}
    if board:
        return "changes the simulated board: " + ", ".join(sorted(board))
    for step in vector["script"]:
        for key in step:
            if key not in ("at_ms", "send", "press", "release", "estop", "expect", "expect_legacy",
                           "expect_seed"):
                return f"uses '{key}'"
    return None


def script(vector, start_ms):
    lines = []
    for step in vector["script"]:
        at = f"at {round((start_ms + step['at_ms']) * 1000)}us"
        if "send" in step:
            lines += [f"{at} send {line}" for line in step["send"].split("\n")]
        for key in ("press", "release"):
            if key in step:
                motor, end = step[key]
                lines.append(f"{at} {key} {motor} {end}")
        if "estop" in step:
            lines.append(f"{at} estop" + ("" if step["estop"] else " release"))
    return "\n".join(lines) + "\n"


def expected(vector, key):
    """Everything the vector expects under `key` (replies or events), and whether the last such
    expectation comes after the vector's last action (then nothing more may come)."""
    lines, last_expect, last_action = [], -1, -1
    for i, step in enumerate(vector["script"]):
        if any(k in step for k in ("send", "press", "release", "estop")):
            last_action = i
        if key in step.get("expect", {}):
            lines += step["expect"][key]
            last_expect = i
    return lines, last_expect >= 0, last_expect >= last_action


def main(directory, emu, image):
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
                     "--max-time", str(end_ms / 1000)],
                    stdin=quiet_in, capture_output=True, timeout=300)
                os.close(quiet_in)
                os.close(keep_open)
                played += 1
                lines = run.stdout.decode("latin-1").splitlines()
                got = {"events": [l for l in lines if l.split("#")[2:3] and l.split("#")[2].startswith("EV")]}
                got["replies"] = [l for l in lines if l not in got["events"]]
                problems = []
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
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
