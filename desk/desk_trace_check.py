#!/usr/bin/python3
"""desk_test's second part: checks what the simulated board received while hmc-desk ran the
camera slider's profile script (desk_test.sh): the frames of set zero, the keyboard jog, a saved
position, the gamepad's runs and stops, and the positions file.

Usage: desk_trace_check.py TRACE.jsonl POSITIONS.json PROFILE_PATH
"""
import json
import sys

TICKS_PER_MS = 48000  # the board's 48 MHz clock, the trace's time unit

trace_path, positions_path, profile_path = sys.argv[1:4]
events = [json.loads(line) for line in open(trace_path) if line.strip()]
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def frames(command):
    """(time, [fields...]) of every frame the board received with this command."""
    out = []
    for e in events:
        if e.get("ev") == "rx" and ("#%s#" % command) in e["line"]:
            out.append((e["t"], e["line"].split("#")[3:-2]))
    return out


# Set zero here: POS 1 0 0, answered with an acceptance, then LIM with the slide's 0-310 mm
# (310 mm = 24800 steps of 1/16 = 1550 full steps = 396800 in 1/256 step).
pos = frames("POS")
check([f for _, f in pos] == [["1", "0", "0"]], "set zero: POS 1 0 0, once: %s" % pos)
if pos:
    after = [e for e in events if e["t"] >= pos[0][0] and e.get("ev") == "tx"]
    check(bool(after) and "#NAK#" not in after[0]["line"], "set zero: the board accepted POS: %s" % after[:1])
lim = frames("LIM")
check(["1", "0", "0", "0", "396800"] in [f for _, f in lim], "set zero: the soft limits sent as LIM 1 0 0 0 396800: %s" % lim)

stm = frames("STM")
moves1 = [(f[1], f[3], f[4]) for _, f in stm if f[0] == "1" and f[1] != "0"]
# 1 mm, +10 mm, +0.1 mm; saved at 11.1 mm, -10 mm, back to 11.1 mm; -100 mm stops at 0 mm;
# go to 400 mm refused; go to 25 mm; the stick up to the 310 mm limit. 50 mm/s: 250 us a step.
expected = [("1", "80"), ("1", "800"), ("1", "8"), ("2", "800"), ("1", "800"), ("2", "888"), ("1", "2000"),
            ("1", "22800")]
check([(a, s) for a, s, _ in moves1] == expected, "slide moves (action, steps): %s, expected %s" % (moves1, expected))
check(all(d == "250" for _, _, d in moves1), "slide moves at the profile's 50 mm/s (250 us): %s" % moves1)
moves2 = [(f[1], f[3]) for _, f in stm if f[0] == "2" and f[1] != "0"]
check(moves2 == [("1", "10")], "Up: motor 2 (no profile axis) 10 steps, once (go to 'start' finds it there): %s" % moves2)

# The stick: the slide's run to its limit stopped when the stick was let go, well before the limit.
stick_t = [t for t, f in stm if f[0] == "1" and f[3] == "22800"]
stops1 = [t for t, f in stm if f[0] == "1" and f[1] == "0" and stick_t and t > stick_t[0]]
check(bool(stops1) and (stops1[0] - stick_t[0]) < 2000 * TICKS_PER_MS,
      "stick let go: a stop for the slide %s ms after its run" % ((stops1[0] - stick_t[0]) // TICKS_PER_MS if stops1 else "-"))

# Motor 3: runs (0 steps: until stopped). B: stops for all three; focus lost: a stop, and no run
# when the focus came back; the panel hanging: the worker's stop before the stick was let go.
runs3 = [(t, f) for t, f in stm if f[0] == "3" and f[1] != "0"]
check([(f[1], f[3], f[4]) for _, f in runs3[:3]] == [("1", "0", "1600"), ("1", "0", "1000"), ("1", "0", "1000")],
      "right stick up: runs of motor 3 at 5/8 and 8/8 of 1000 steps/s: %s" % [f for _, f in runs3])
stops = lambda m, after, before: [t for t, f in stm if f[0] == m and f[1] == "0" and after < t < before]
if len(runs3) >= 4:
    t_b, t_focus, t_hang, t_space = (t for t, _ in runs3[:4])
    check(all(stops(m, t_b, t_focus) for m in "123"), "B: a stop for every motor")
    check(len(stops("3", t_focus, t_hang)) >= 1, "focus lost: motor 3 stopped")
    hang_stops = stops("3", t_hang, t_space)
    check(bool(hang_stops) and hang_stops[0] - t_hang < 1150 * TICKS_PER_MS,
          "panel hung 1.2 s: motor 3 stopped %s ms after its run, before the stick was let go" %
          ((hang_stops[0] - t_hang) // TICKS_PER_MS if hang_stops else "-"))
    # An absolute target: from where the stick left motor 3 (1/256 step in the trace; 1/16 steps).
    before = [e["pos"] for e in events if e.get("ev") == "step" and e["motor"] == 3 and e["t"] < t_space]
    here = (before[-1] if before else 0) // 16
    check(here > 0 and here + int(runs3[3][1][3]) == 400000,
          "go to 400000 (steps) on motor 3: from %d, %s steps more" % (here, runs3[3][1][3]))
    check(all(stops(m, t_space, runs3[4][0] if len(runs3) > 4 else float("inf")) for m in "123"),
          "space: a stop for every motor")
check(len(runs3) == 5, "no run of motor 3 other than the stick's three, the go-to and the last: %d" % len(runs3))
if len(runs3) == 5:
    check(all(stops(m, runs3[4][0], float("inf")) for m in "123"), "the window closed with a stick held: a stop for every motor")

positions = json.load(open(positions_path))
saved = positions.get("profiles", {}).get(profile_path, [])
check(saved == [{"name": "start", "axes": {"motor 2": 10, "motor 3": 0, "slide": 11.1}}],
      "positions file: 'start' with the slide at 11.1 mm: %s" % saved)

sys.exit(1 if failures else 0)
