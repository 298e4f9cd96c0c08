#!/usr/bin/python3
"""How closely `hmc grbl` moves follow each other on the board, measured in the simulated board's
trace in real time (sim://, not fast; 115200 baud paced both ways): for every two-axis segment,
the start skew between its axes (when each STM line had arrived, and each motor's first STEP
edge), the pause from a segment's last STEP edge to the next one's first (which holds the last
and first step intervals of the ramps), and the host's part of it: from the board sending the
segment's last EVD to the next segment's first STM line having arrived. Two programs: a
zig-zag whose segments keep the same axis shares (no SET lines between them) and an arc, whose
chords change the shares (a SET of each motor's acceleration before its STM).
Usage: grbl_segments.py HMC_BINARY"""
import json, os, re, signal, statistics, subprocess, sys, tempfile, time

import serial

hmc = os.path.abspath(sys.argv[1])
work = tempfile.mkdtemp()
env = dict(os.environ, HMC_SIM_STATE=os.path.join(work, "state"), XDG_CONFIG_HOME=work)
env.pop("HMC_PORT", None)
env.pop("HMC_PROFILE", None)


def run(program, name):
    trace = os.path.join(work, name + ".jsonl")
    err = open(os.path.join(work, name + ".err"), "w+")
    proc = subprocess.Popen([hmc, "--port", "sim://%s?fresh&nosave&trace=%s" % (name, trace), "grbl", "--pty"],
                            stderr=err, stdout=subprocess.DEVNULL, env=env)
    path = None
    for _ in range(500):
        err.seek(0)
        m = re.search(r"hmc grbl: pty (\S+)", err.read())
        if m:
            path = m.group(1)
            break
        time.sleep(0.02)
    port = serial.Serial(path, 115200, timeout=0.05)
    pending, buffer = [], b""
    for line in program + ["G4 P0"]:
        while sum(pending) + len(line) + 1 > 128:
            buffer += port.read(64)
            while b"\n" in buffer:
                got, buffer = buffer.split(b"\n", 1)
                if got.strip() in (b"ok",) or got.startswith(b"error"):
                    pending.pop(0)
        port.write((line + "\n").encode())
        pending.append(len(line) + 1)
    while pending:
        buffer += port.read(64)
        while b"\n" in buffer:
            got, buffer = buffer.split(b"\n", 1)
            if got.strip() == b"ok" or got.startswith(b"error"):
                pending.pop(0)
    port.close()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=10)
    with open(trace) as f:
        return [json.loads(l) for l in f if l.strip()]


def measure(events):
    """Segments: the STM lines received together, and the steps until the next such burst."""
    segments = []
    for e in events:
        if e.get("ev") == "tx" and "#EVD#" in e["line"] and segments:
            segments[-1]["evd"] = e["t"]
        if e.get("ev") == "rx" and "#STM#" in e["line"]:
            motor = int(e["line"].split("#")[3])
            if not segments or segments[-1]["steps"]:
                segments.append({"rx": {}, "first": {}, "last": {}, "steps": 0})
            segments[-1]["rx"][motor] = e["t"]
        elif e.get("ev") == "step" and segments:
            s = segments[-1]
            s["first"].setdefault(e["motor"], e["t"])
            s["last"][e["motor"]] = e["t"]
            s["steps"] += 1
    ms = lambda ticks: ticks / 48000.0
    rx_skew = [ms(max(s["rx"].values()) - min(s["rx"].values())) for s in segments if len(s["rx"]) > 1]
    step_skew = [ms(max(s["first"].values()) - min(s["first"].values())) for s in segments if len(s["first"]) > 1]
    end_skew = [ms(max(s["last"].values()) - min(s["last"].values())) for s in segments if len(s["last"]) > 1]
    gaps = [ms(min(b["first"].values()) - max(a["last"].values())) for a, b in zip(segments, segments[1:])
            if a["last"] and b["first"]]
    turnaround = [ms(min(b["rx"].values()) - a["evd"]) for a, b in zip(segments, segments[1:]) if "evd" in a]
    return rx_skew, step_skew, end_skew, gaps, turnaround


def show(name, values):
    print("  %-48s median %6.2f ms, max %6.2f ms (%d)" % (name, statistics.median(values), max(values), len(values)))
    return statistics.median(values)


zigzag = ["G21 G90 G1 F1500"] + ["G1 X%d Y%d" % (2 * (i + 1), 2 * ((i + 1) % 2)) for i in range(20)]
arc = ["G21 G90 G1 X10 Y0 F1500", "G3 X-10 Y0 I-10 J0"]
figures = {}
for name, program in (("zigzag", zigzag), ("arc", arc)):
    rx_skew, step_skew, end_skew, gaps, turnaround = measure(run(program, name))
    print("%s: %d segments" % (name, len(gaps) + 1))
    figures[name] = (show("STM lines' arrival, first to last axis", rx_skew), show("first STEP edges, first to last axis", step_skew),
                     show("last STEP edges, first to last axis", end_skew), show("pause: last STEP to the next segment's first", gaps),
                     show("host: last EVD sent to the next STM received", turnaround))
print("summary: | hmc grbl: two-axis start skew (STM arrival) | %.2f ms | | | ≈ one STM line, 2.9 ms at 115200 |" % figures["zigzag"][0])
print("summary: | hmc grbl: pause between segments, same shares | %.2f ms | | | |" % figures["zigzag"][3])
print("summary: | hmc grbl: pause between arc chords (SET + STM) | %.2f ms | | | |" % figures["arc"][3])
print("summary: | hmc grbl: last EVD sent to the next STM received | %.2f ms | | | |" % figures["zigzag"][4])
