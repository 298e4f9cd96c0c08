#!/usr/bin/env python3
"""The firmware's main loop in cycles on the real image, and the link watchdog's share of it
(scripts/bench main-loop; docs/performance.md, "The link watchdog in the main loop").

Each case boots hmc-firmware.elf in hmc-emu --fast, ends the power-up self-test with a stop (STM 1 0), and
takes hmc-emu --stats from --measure-from to --max-time with --count-calls on
Controller::poll: the cycles spent in thread mode (outside every interrupt: the main loop, which
calls poll() once a round) over the calls counted, i.e. cycles per round of the main loop, the
LED, servo and buzzer services and the chip watchdog's kick included. Lines arrive from an
hmc-emu script at a fixed period; a line end's cost is what its rounds took above idle rounds:
(thread cycles - rounds x idle cycles per round) / lines.

Usage: main_loop.py HMC_EMU IMAGE
"""
import os
import re
import subprocess
import sys
import tempfile

MEASURE_FROM = 0.3  # s of virtual time: the boot and the self-test are over
MEASURE_TO = 1.3
LINE_PERIOD_MS = 10  # keep-alive lines (a bare line feed) in the cases with lines
POLL = "hmc::fw::Controller::poll"


def frame(name, *values):
    return "STX#%d#%s#%s#%d#ETX" % (len(values) + 1, name, "#".join(str(v) for v in values),
                                    sum(values) % 256)


def run(watchdog_ms, lines):
    script = ["at 0s send " + frame("STM", 1, 0, 0, 0, 0)]  # a stop: the power-up self-test ends
    if watchdog_ms:
        script.append("at 1ms send " + frame("WDG", watchdog_ms))
    sent = 0
    if lines:
        t = 100
        while t < MEASURE_TO * 1000:
            script.append("at %dms send " % t)  # a bare line feed: the host's keep-alive
            if MEASURE_FROM * 1000 <= t < MEASURE_TO * 1000:
                sent += 1
            t += LINE_PERIOD_MS
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        f.write("\n".join(script) + "\n")
        path = f.name
    try:
        # Standard input stays open until hmc-emu stops at --max-time (at its end hmc-emu would
        # stop once the replies are quiet).
        held, keep = os.pipe()
        try:
            done = subprocess.run([EMU, IMAGE, "--fast", "--stats", "--count-calls", POLL,
                                   "--measure-from", str(MEASURE_FROM), "--max-time", str(MEASURE_TO),
                                   "--script", path],
                                  stdin=held, capture_output=True, text=True, timeout=300)
        finally:
            os.close(held)
            os.close(keep)
    finally:
        os.unlink(path)
    replies = done.stdout.splitlines()
    if any("NAK" in r for r in replies):
        sys.exit("main-loop: the image refused a line: %s" % replies)
    if watchdog_ms and not any(r.startswith("STX#1#ACK#") for r in replies):
        sys.exit("main-loop: WDG was not acknowledged: %s" % replies)
    if any(re.match(r"STX#5#EVD#\d#6#", r) for r in replies):
        sys.exit("main-loop: the link watchdog fired: %s" % replies)
    if "--max-time reached at %.6f s" % MEASURE_TO not in done.stderr:
        sys.exit("main-loop: hmc-emu stopped early:\n" + done.stderr)
    window = re.search(r"measured from ([\d.]+) s to ([\d.]+) s: (\d+) cycles", done.stderr)
    thread = re.search(r"thread mode \(the main loop\): (\d+) cycles", done.stderr)
    calls = re.search(re.escape(POLL) + r": (\d+) calls", done.stderr)
    if not window or not thread or not calls:
        sys.exit("main-loop: no figures from hmc-emu:\n" + done.stderr)
    return {"cycles": int(window.group(3)), "thread": int(thread.group(1)),
            "polls": int(calls.group(1)), "lines": sent}


def main():
    global EMU, IMAGE
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    EMU, IMAGE = sys.argv[1], sys.argv[2]
    off = run(0, False)
    armed = run(500, True)  # armed, kept alive by the lines
    off_lines = run(0, True)
    armed_idle = run(60000, False)  # armed, no line in the window (500 ms would fire)
    idle_off = off["thread"] / off["polls"]
    idle_armed = armed_idle["thread"] / armed_idle["polls"]

    def per_line(case, idle):
        return (case["thread"] - case["polls"] * idle) / case["lines"]

    line_off = per_line(off_lines, idle_off)
    line_armed = per_line(armed, idle_armed)
    print("| case | rounds of the main loop | thread-mode cycles | of the CPU | lines | cycles per idle round | cycles per line end |")
    print("|---|---|---|---|---|---|---|")
    for name, case, idle, line in (("watchdog off, idle", off, idle_off, None),
                                   ("watchdog armed (WDG 60000), idle", armed_idle, idle_armed, None),
                                   ("watchdog off, a line every %d ms" % LINE_PERIOD_MS, off_lines, idle_off, line_off),
                                   ("watchdog armed (WDG 500), a line every %d ms" % LINE_PERIOD_MS, armed, idle_armed, line_armed)):
        print("| %s | %d | %d | %.1f %% | %d | %.1f | %s |" % (
            name, case["polls"], case["thread"], 100.0 * case["thread"] / case["cycles"], case["lines"], idle,
            "%.0f" % line if line is not None else "-"))
    print()
    print("summary: | main loop round on the real image, idle | %.1f cycles (watchdog off), %.1f (armed): +%.1f | "
          "bench/qemu: +9 instructions | - | - |" % (idle_off, idle_armed, idle_armed - idle_off))
    print("summary: | a received line end in the main loop | %.0f cycles (watchdog off), %.0f (armed): +%.0f | "
          "bench/qemu: +76 instructions | - | - |" % (line_off, line_armed, line_armed - line_off))


if __name__ == "__main__":
    main()
