#!/usr/bin/env python3
"""Cycles per step of the real firmware image's step interrupt, measured in hmc-emu's cycle model
(scripts/bench cycles; docs/performance.md, "Cycles on the real image").

Each case boots hmc-firmware.elf in hmc-emu --fast, sends the frames that start its motors (the
first one also ends the power-up self-test), and takes hmc-emu --stats from --measure-from to
--max-time: the step interrupts' cycles (one per motor's compare: TC4, TCC1, TCC2, exceptions 35,
32, 33, summed), entry and return, flash wait states and the timers' synchronisation included, over the STEP rising edges the emulated board
counted. Beside them: bench/qemu's instruction counts of the same engine (the core alone, a fake
port), Klipper's cycles per step on the SAMD21, and issue 18's targets. At a constant rate, from
--stats and --trace: the widest miss of a rise-to-rise time against the move's delay, and the
share of rises more than one tick off it.

With a fourth argument, bench/qemu's output under hmc-emu-bench --cycles (the same program in the
cycle model): the main loop's StepScheduler::fill per step while ramping and its share of the CPU,
beside the figures of the engine that computed every ramp step (main f26254f, measured the same
way: issue 18's "today").

Usage: cycles.py HMC_EMU IMAGE [QEMU_BENCH_OUTPUT [FILL_CYCLES_OUTPUT]]
"""
import json
import re
import subprocess
import sys
import tempfile

MEASURE_FROM = 0.3  # s of virtual time: the boot, the self-test's end and the starts are over
MEASURE_TO = 1.2
TICKS_PER_SECOND = 48000000  # the trace's times
# The step interrupts' exception numbers (16 + IRQ): TCC1 (motor 2), TCC2 (motor 3), TC4 (motor 1).
STEP_EXCEPTIONS = (32, 33, 35)


def frame(name, *values):
    return "STX#%d#%s#%s#%d#ETX\n" % (len(values) + 1, name, "#".join(str(v) for v in values),
                                      sum(values) % 256)


def run(moves, accel=0):
    """moves: [(motor, delay_us)]; all forward at 1/256 (no switch reached in the window)."""
    lines = []
    for motor, _ in moves:
        lines.append(frame("SET", motor, 3, accel))
    for motor, delay in moves:
        lines.append(frame("STM", motor, 1, 256, 0, delay))
    # Standard input stays open until hmc-emu stops at --max-time (at its end hmc-emu would stop
    # once the replies are quiet).
    trace = tempfile.NamedTemporaryFile(prefix="cycles-trace-", suffix=".jsonl")
    emu = subprocess.Popen([EMU, IMAGE, "--fast", "--quiet", "--stats", "--measure-from",
                            str(MEASURE_FROM), "--max-time", str(MEASURE_TO), "--trace", trace.name],
                           stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    emu.stdin.write("".join(lines))
    emu.stdin.flush()
    stdout, stderr = emu.stdout.read(), emu.stderr.read()
    emu.wait()
    emu.stdin.close()
    done = subprocess.CompletedProcess(emu.args, emu.returncode, stdout, stderr)
    replies = done.stdout.splitlines()
    refused = [r for r in replies if "NAK" in r]
    if refused:
        if all(r.startswith("STX#4#NAK#15#") for r in refused):  # rate_limit: over the budget
            return None
        sys.exit("cycles: the image refused a frame: %s" % refused)
    window = re.search(r"measured from ([\d.]+) s to ([\d.]+) s: (\d+) cycles.*?(\d+) flash wait "
                       r"cycles; steps (\d+) (\d+) (\d+)", done.stderr)
    # The three step interrupts (one per motor's compare), summed.
    handlers = [tuple(int(v) for v in h) for h in re.findall(
        r"exception (\d+): (\d+) entries, [\d.]+ cycles each, (\d+) cycles .*?, "
        r"(\d+) instructions, (\d+) flash wait cycles", done.stderr)
        if int(h[0]) in STEP_EXCEPTIONS]
    if not window or not handlers:
        sys.exit("cycles: no figures from hmc-emu:\n" + done.stderr)
    steps = sum(int(window.group(i)) for i in (5, 6, 7))
    expected = len(moves)
    moving = sum(1 for i in (5, 6, 7) if int(window.group(i)) > 0)
    if moving != expected:
        sys.exit("cycles: %d motors stepped, %d expected:\n%s" % (moving, expected, done.stderr))
    seconds = float(window.group(2)) - float(window.group(1))
    # STEP pulse timing over the window, the worst of the motors (hmc-emu --stats, in ns).
    pulses = re.findall(r"STEP (\d): \d+ pulses, high ([\d.]+)-([\d.]+) ns, low >= ([\d.-]+) ns, "
                        r"period ([\d.]+)-([\d.]+) ns", done.stderr)
    # At a constant rate every rise should follow the one before by the move's delay exactly:
    # the widest miss of any motor's rise-to-rise time (ns), and the share of rises off it.
    off, late = None, None
    if accel == 0:
        delays = dict(moves)
        off = max((max(abs(float(p[4]) - delays[int(p[0])] * 1000),
                       abs(float(p[5]) - delays[int(p[0])] * 1000))
                   for p in pulses if int(p[0]) in delays), default=-1)
        late = off_schedule_share(trace.name, delays)
    return {
        "late_share": late,
        "high_min": min(float(p[1]) for p in pulses) if pulses else -1,
        "high_max": max(float(p[2]) for p in pulses) if pulses else -1,
        "low_min": min(float(p[3]) for p in pulses) if pulses else -1,
        "off_schedule": off,
        "steps": steps,
        "rate": steps / seconds,
        "entries": sum(h[1] for h in handlers),
        "per_entry": sum(h[2] for h in handlers) / sum(h[1] for h in handlers),
        "per_step": sum(h[2] for h in handlers) / steps,
        "share": 100.0 * sum(h[2] for h in handlers) / int(window.group(3)),
        "instructions": sum(h[3] for h in handlers) / steps,
        "isr_waits": sum(h[4] for h in handlers) / steps,
    }


def off_schedule_share(trace_path, delays):
    """The share (%) of the STEP rises from MEASURE_FROM on (hmc-emu --trace: times in 48 MHz
    ticks) that come more than one tick off the previous rise + the move's delay."""
    last, rises, off = {}, 0, 0
    with open(trace_path) as trace:
        for line in trace:
            event = json.loads(line)
            if event.get("ev") != "step" or event["t"] < MEASURE_FROM * TICKS_PER_SECOND:
                continue
            motor, t = event["motor"], event["t"]
            if motor in last:
                rises += 1
                off += abs(t - last[motor] - delays[motor] * TICKS_PER_SECOND // 1000000) > 1
            last[motor] = t
    return 100.0 * off / rises if rises else -1


def qemu_rows(path):
    rows = {}
    if path:
        for line in open(path):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) == 7 and cells[1].isdigit():
                rows[cells[0]] = cells[4]
    return rows


def fill_rows(path):
    """bench/qemu's scenario rows: fill per step (last cell); the share rows: fill per 1 000 ticks."""
    fill, share = {}, {}
    if path:
        for line in open(path):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) == 7 and cells[1].isdigit():
                fill[cells[0]] = float(cells[6])
            elif len(cells) == 3 and cells[1].isdigit():
                share[cells[0]] = float(cells[2])
    return fill, share


EMU, IMAGE = sys.argv[1], sys.argv[2]
qemu = qemu_rows(sys.argv[3] if len(sys.argv) > 3 else None)
FILL, SHARE = fill_rows(sys.argv[4] if len(sys.argv) > 4 else None)

# fill() per step in cycles (hmc-emu-bench --cycles) with one segment per ramp step: main f26254f.
FILL_BEFORE = {
    "1 motor, ramping": 1688.3,
    "3 motors, ramping": 1838.3,
    "3 motors toward 20 us, ramping": 1299.7,
    "3 motors to 20 us and back, ramping, fill every 250 us": 376.5,
    "3 motors to 20 us and back at 200 000 steps/s^2, fill every 250 us": 791.4,
}
SHARE_BEFORE = {
    "3 motors to 20 us and back, ramping, fill every 250 us": 830.5,
    "3 motors to 20 us and back at 200 000 steps/s^2, fill every 250 us": 1236.5,
}

# Cycles a step with one compare for all three motors (main 85dc070, this script then), beside
# the engine with one compare a motor; "refused": over that image's budget (100 000 / 80 000).
CYCLES_BEFORE = {
    "1 motor, constant rate (100 us)": "204",
    "1 motor, ramping toward 25 us (40 000 steps/s^2)": "219",
    "3 motors, constant rate (100, 130, 177 us)": "219",
    "3 motors, constant rate (40 us each: 75 000 steps/s, the budget before the DMA pulses)": "214",
    "3 motors, constant rate (31 us each: 96 777 steps/s, the budget before the compare per motor)":
        "213",
    "2 motors at the spec's fastest, constant rate (20 us each: 100 000 steps/s)": "204",
    "3 motors ramping toward 76 us (13 157 steps/s^2 each)": "238",
}

# (case, moves, acceleration, bench/qemu's row, Klipper's cycles per step, issue 18's target)
CASES = [
    ("1 motor, constant rate (100 us)", [(1, 100)], 0, "1 motor, constant rate", 70, 140),
    ("1 motor, ramping toward 25 us (40 000 steps/s^2)", [(1, 25)], 40000, "1 motor, ramping", 70, 150),
    ("3 motors, constant rate (100, 130, 177 us)", [(1, 100), (2, 130), (3, 177)], 0,
     "3 motors, constant rate", 102, 120),
    ("3 motors, constant rate (40 us each: 75 000 steps/s, the budget before the DMA pulses)",
     [(1, 40), (2, 40), (3, 40)], 0, "3 motors, constant rate, same grid", 102, 120),
    ("3 motors, constant rate (31 us each: 96 777 steps/s, the budget before the compare per motor)",
     [(1, 31), (2, 31), (3, 31)], 0, "-", 102, 120),
    ("2 motors at the spec's fastest, constant rate (20 us each: 100 000 steps/s)",
     [(1, 20), (2, 20)], 0, "-", 102, 120),
    ("3 motors ramping toward 76 us (13 157 steps/s^2 each)", [(1, 76), (2, 76), (3, 76)], 13157,
     "3 motors, ramping", 102, 160),
    ("3 motors at the spec's fastest, constant rate (20 us each: 150 000 steps/s, the budget)",
     [(1, 20), (2, 20), (3, 20)], 0, "-", 102, 120),
    ("3 motors ramping toward the spec's fastest (20 us each at 50 000 steps/s^2: up to 150 000 "
     "steps/s, the budget)", [(1, 20), (2, 20), (3, 20)], 50000, "-", 102, 160),
]

print("Step interrupt of the real image (hmc-firmware.elf, real HAL) in hmc-emu's cycle model, "
      "from %.1f s to %.1f s of virtual time at 48 MHz:" % (MEASURE_FROM, MEASURE_TO))
print()
print("| case | steps/s | cycles per step | before: one compare for all three (main 85dc070) | "
      "of which flash wait states | instructions per step | "
      "cycles per interrupt | CPU share | STEP high (ns) | STEP low, shortest (ns) | "
      "rise to rise, widest miss of the delay (ns) | rises more than a tick off it | "
      "bench/qemu instructions per step (core, fake port) | Klipper cycles per step | "
      "issue 18 target |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
results = []
for name, moves, accel, qemu_row, klipper, target in CASES:
    r = run(moves, accel)
    if r is None:
        print("| %s | refused: over the image's step budget (rate_limit) | | %s | | | | | | | | | | %d | <= %d |"
              % (name, CYCLES_BEFORE.get(name, "refused"), klipper, target))
        continue
    results.append((name, r, klipper, target))
    off = "-" if r["off_schedule"] is None else "%.0f" % r["off_schedule"]
    late = "-" if r["late_share"] is None else "%.2f %%" % r["late_share"]
    print("| %s | %.0f | %.1f | %s | %.1f | %.1f | %.1f | %.1f %% | %.0f-%.0f | %.0f | %s | %s | %s | %d | <= %d |" % (
        name, r["rate"], r["per_step"], CYCLES_BEFORE.get(name, "refused"), r["isr_waits"],
        r["instructions"], r["per_entry"],
        r["share"], r["high_min"], r["high_max"], r["low_min"], off, late,
        qemu.get(qemu_row, "-"), klipper, target))
print()
for name, r, klipper, target in results:
    print("summary: | firmware step interrupt on the real image (hmc-emu cycles), %s | %.0f cycles per "
          "step | Klipper on the SAMD21: %d cycles per step | %.1fx | <= %d (issue 18) |" % (
              name, r["per_step"], klipper, r["per_step"] / klipper, target))

if FILL:
    print()
    print("The main loop's StepScheduler::fill while ramping (bench/qemu's program in hmc-emu's "
          "cycle model; its fill() after every interrupt, or every 250 us where the case says "
          "so), cycles per step, beside the engine that computed every ramp step (main f26254f):")
    print()
    print("| case | fill per step, ramp segments | fill per step, one segment a step | ratio |")
    print("|---|---|---|---|")
    for name, before in FILL_BEFORE.items():
        if name in FILL:
            print("| %s | %.1f | %.1f | %.2fx |" % (name, FILL[name], before, before / FILL[name]))
    print()
    print("| case | main loop's share of the CPU (fill), ramp segments | one segment a step |")
    print("|---|---|---|")
    for name, before in SHARE_BEFORE.items():
        if name in SHARE:
            print("| %s | %.1f %% | %.1f %% |" % (name, SHARE[name] / 10, before / 10))
    for name, before in FILL_BEFORE.items():
        if name in FILL:
            print("summary: | firmware main loop fill() per ramping step (hmc-emu cycles), %s | "
                  "%.0f cycles per step | one segment a step (main f26254f): %.0f | %.2fx | "
                  "ramp segments {interval, add, count} (issue 18) |"
                  % (name, FILL[name], before, before / FILL[name]))
