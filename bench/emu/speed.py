#!/usr/bin/env python3
"""hmc-emu's speed against real time (scripts/bench emu-speed; docs/emu.md, "Speed").

Boots the real image with three motors at 40 us each (75 000 steps/s summed, the step budget
when this bench was written), the frames on standard input kept open, once in --fast (2 s of
virtual time) and once in real-time mode (5 s), and reports virtual seconds per CPU second and
per wall second, with the machine's load average: real-time mode keeps up when its wall ratio
is 1.00.

Usage: speed.py HMC_EMU IMAGE
"""
import os
import re
import subprocess
import sys

EMU, IMAGE = sys.argv[1], sys.argv[2]


def frame(name, *values):
    return "STX#%d#%s#%s#%d#ETX\n" % (len(values) + 1, name, "#".join(str(v) for v in values),
                                      sum(values) % 256)


FRAMES = "".join(frame("SET", m, 3, 0) for m in (1, 2, 3)) + \
    "".join(frame("STM", m, 1, 256, 0, 40) for m in (1, 2, 3))


def run(fast, seconds):
    args = [EMU, IMAGE] + (["--fast"] if fast else []) + [
        "--stats", "--quiet", "--max-time", str(seconds), "--measure-from", "0.3"]
    load = os.getloadavg()[0]
    emu = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
    emu.stdin.write(FRAMES)
    emu.stdin.flush()
    stderr = emu.stderr.read()
    _, _, usage = os.wait4(emu.pid, 0)
    emu.stdin.close()
    # hmc-emu's own wall time: from its start of emulation (after loading the image) to its end.
    virtual = re.search(r"([\d.]+) s virtual in ([\d.]+) s wall", stderr)
    steps = re.search(r"measured from ([\d.]+) s to ([\d.]+) s: .*?steps (\d+) (\d+) (\d+)", stderr)
    if not virtual or not steps:
        sys.exit("emu-speed: no figures from hmc-emu:\n" + stderr)
    rate = sum(int(steps.group(i)) for i in (3, 4, 5)) / (float(steps.group(2)) - float(steps.group(1)))
    if rate < 74000:
        sys.exit("emu-speed: the board made %.0f steps/s, not the 75 000 asked for:\n%s" % (rate, stderr))
    cpu = usage.ru_utime + usage.ru_stime
    v, wall = float(virtual.group(1)), float(virtual.group(2))
    return {"virtual": v, "cpu": cpu, "wall": wall, "per_cpu": v / cpu, "per_wall": v / wall,
            "load": load, "rate": rate}


fast = run(True, 2)
real = run(False, 5)
print("| mode | virtual time | steps/s | CPU | wall | virtual/CPU | virtual/wall | load average |")
print("|---|---|---|---|---|---|---|---|")
for name, r in (("--fast", fast), ("real time", real)):
    print("| %s | %.1f s | %.0f | %.2f s | %.2f s | %.2fx | %.2fx | %.1f |" % (
        name, r["virtual"], r["rate"], r["cpu"], r["wall"], r["per_cpu"], r["per_wall"], r["load"]))
print("summary: | hmc-emu, three motors at 75 000 steps/s | --fast %.2fx real time per CPU second; "
      "real-time mode %.2fx of the wall clock on %.2f of a core (load %.1f) | the chip: 1x | %.2fx | "
      ">= 1x in real-time mode (issue 17) |" % (
          fast["per_cpu"], real["per_wall"], real["cpu"] / real["wall"], real["load"],
          real["per_wall"]))
