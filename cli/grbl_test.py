#!/usr/bin/python3
"""`hmc grbl --pty` driven by a grbl streaming client written here with pyserial (Debian's
python3-serial): grbl's character counting (never more than 128 unanswered bytes), a program with
a square, an arc, a servo, an LED and a dwell, bad input, and a sender that goes away mid-move.
What the board did is read from the simulated board's trace: STEP edges per motor, the servo's
pulse, the LED's colour.
With hmc-sim (a board on TCP with a control channel): a limit switch and the emergency switch
pressed during moves are ALARM:1 and ALARM:3, and the link watchdog is armed.
Usage: grbl_test.py HMC_BINARY HMC_SIM_BINARY SOURCE_DIR"""
import json, math, os, re, signal, subprocess, sys, tempfile, time

import serial

hmc, sim = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
work = tempfile.mkdtemp()
trace = os.path.join(work, "trace.jsonl")
env = dict(os.environ, HMC_SIM_STATE=os.path.join(work, "state"))
env.pop("HMC_PORT", None)
env.pop("HMC_PROFILE", None)
env["XDG_CONFIG_HOME"] = work  # no profile: X, Y, Z are motors 1-3 at 80 steps/mm
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def start():
    err = open(os.path.join(work, "hmc.err"), "w+")
    proc = subprocess.Popen([hmc, "--port", "sim://grbl?fast&fresh&nosave&trace=" + trace, "grbl", "--pty"],
                            stderr=err, stdout=subprocess.DEVNULL, env=env)
    for _ in range(500):
        err.seek(0)
        m = re.search(r"hmc grbl: pty (\S+)", err.read())
        if m:
            return proc, err, m.group(1)
        if proc.poll() is not None:
            break
        time.sleep(0.02)
    err.seek(0)
    raise RuntimeError("hmc grbl did not start: " + err.read())


def read_line(port, deadline=10.0):
    end = time.time() + deadline
    line = b""
    while time.time() < end:
        c = port.read(1)
        if not c:
            continue
        if c == b"\n":
            return line.rstrip(b"\r").decode("latin-1")
        line += c
    raise TimeoutError("no line from hmc grbl; so far: %r" % line)


def answer(port, messages=None):
    """The next ok/error:N (or ALARM) line; [MSG:...] and other lines go to `messages`."""
    while True:
        line = read_line(port)
        if line == "ok" or line.startswith("error:"):
            return line
        if messages is not None:
            messages.append(line)


def stream(port, lines):
    """grbl's character-counting protocol: send while the unanswered bytes fit 128."""
    sent, answers, pending, messages = 0, [], [], []
    while len(answers) < len(lines):
        while sent < len(lines) and sum(pending) + len(lines[sent]) + 1 <= 128:
            port.write((lines[sent] + "\n").encode())
            pending.append(len(lines[sent]) + 1)
            sent += 1
        check(sum(pending) <= 128, "more than 128 bytes unanswered")
        answers.append(answer(port, messages))
        pending.pop(0)
    return answers, messages


def status(port):
    port.write(b"?")
    while True:
        line = read_line(port)
        if line.startswith("<"):
            return line


def wait_idle(port, limit=60):
    end = time.time() + limit
    while time.time() < end:
        s = status(port)
        if s.startswith("<Idle"):
            return s
        time.sleep(0.05)
    raise TimeoutError("not idle: " + s)


def trace_events():
    with open(trace) as f:
        return [json.loads(l) for l in f if l.strip()]


def step_edges():
    edges = {}
    for e in trace_events():
        if e.get("ev") == "step":
            edges[e["motor"]] = edges.get(e["motor"], 0) + 1
    return edges


def arc_chords(start, end, centre, clockwise, tolerance=0.01):
    """The chord ends hmc grbl makes of an arc (grbl's angle rule, the stated tolerance)."""
    r0 = (start[0] - centre[0], start[1] - centre[1])
    rt = (end[0] - centre[0], end[1] - centre[1])
    travel = math.atan2(r0[0] * rt[1] - r0[1] * rt[0], r0[0] * rt[0] + r0[1] * rt[1])
    if clockwise and travel >= -5e-7:
        travel -= 2 * math.pi
    if not clockwise and travel <= 5e-7:
        travel += 2 * math.pi
    radius = math.hypot(*r0)
    n = max(1, math.ceil(abs(travel) / (2 * math.acos(1 - tolerance / radius))))
    a0 = math.atan2(r0[1], r0[0])
    return [(centre[0] + radius * math.cos(a0 + travel * k / n), centre[1] + radius * math.sin(a0 + travel * k / n))
            for k in range(1, n)] + [end]


def steps(mm):
    v = mm * 80
    return int(math.floor(abs(v) + 0.5)) * (1 if v >= 0 else -1)  # C's llround


proc, err, path = start()
port = serial.Serial(path, 115200, timeout=0.05)
check(read_line(port) == "", "the banner starts with an empty line")
check(read_line(port) == "Grbl 1.1h ['$' for help]", "banner")

# A program: a square with an arc for its third side, a servo, an LED cue, a dwell.
program = ["G21 G90", "G1 X20 F3000", "G1 Y20", "G3 X0 Y20 I-10 J0", "G1 Y0",
           "M280 P0 S45", "M150 S0 R0 U0 B255 W0", "G4 P0.1", "M2"]
started = time.time()
answers, messages = stream(port, program)
check(answers == ["ok"] * len(program), "every line of the program answered ok: %s %s" % (answers, messages))
idle = wait_idle(port)
check(idle.startswith("<Idle|MPos:0.000,0.000,0.000|"), "back at the origin: " + idle)
points = [(0, 0), (20, 0), (20, 20)] + arc_chords((20, 20), (0, 20), (10, 20), False) + [(0, 0)]
want_x = sum(abs(steps(b[0]) - steps(a[0])) for a, b in zip(points, points[1:]))
want_y = sum(abs(steps(b[1]) - steps(a[1])) for a, b in zip(points, points[1:]))
edges = step_edges()
check(edges.get(1) == want_x, "X made %s STEP edges, want %d" % (edges.get(1), want_x))
check(edges.get(2) == want_y, "Y made %s STEP edges, want %d" % (edges.get(2), want_y))
check(3 not in edges, "Z did not move")
events = trace_events()
pulse = 544 + (45 * 1856 + 90) // 180  # the board's pulse for 45 degrees (protocol_facts.h)
check(any(e.get("ev") == "servo" and e.get("servo") == 1 and e.get("pulse_us") == pulse for e in events),
      "servo 1 at 45 degrees (%d us)" % pulse)
check(any(e.get("ev") == "led" and e.get("strip") == 1 and (e["r"], e["g"], e["b"], e["w"]) == (0, 0, 255, 0)
          for e in events), "strip 1 blue")
print("program: %d lines in %.2f s; X %d, Y %d STEP edges" % (len(program), time.time() - started, want_x, want_y))

# Bad input: grbl's errors, a message naming what was wrong, nothing moved.
before = step_edges()
for line, want, words in [("G1 X10 F0", "error:22", "feed"), ("G1 X5 Q3 F100", "error:20", "Q3"),
                          ("G0 X" + "1" * 90, "error:11", "80"), ("G0 X\x01\x7f5", "error:1", "0x01"),
                          ("M280 P7 S90", "error:20", "P7"), ("G2 X5 Y5 I1", "error:33", "circle"),
                          ("$J=G1 X5 F10", "error:16", "jog")]:
    port.write(line.encode("latin-1") + b"\n")
    msgs = []
    got = answer(port, msgs)
    check(got == want and any(words in m for m in msgs), "%r -> %s %s, want %s naming %s" % (line, got, msgs, want, words))
port.write(bytes(range(0x80, 0x84)) + b"\xfe\xff\x00\x07garbage\n")
msgs = []
check(answer(port, msgs).startswith("error:"), "binary garbage is an error: %s" % msgs)
check(step_edges() == before, "nothing moved on bad input")
check(proc.poll() is None, "hmc grbl still runs after bad input")

# The sender goes away mid-move: every motor stops.
port.write(b"G1 X300 F300\n")
check(answer(port) == "ok", "the long move is taken")
end = time.time() + 10
while time.time() < end and not status(port).startswith("<Run"):
    time.sleep(0.01)
port.close()
time.sleep(0.5)
moved = step_edges().get(1, 0)
time.sleep(0.5)
check(step_edges().get(1, 0) == moved, "X stopped after the sender went away")
check(moved - edges.get(1, 0) < 300 * 80, "X stopped before the end of its move")
err.seek(0)
check("the sender went away; every motor was stopped" in err.read(), "hmc grbl says the motors were stopped")
port = serial.Serial(path, 115200, timeout=0.05)
lines = [read_line(port) for _ in range(4)]
check(lines[1] == "Grbl 1.1h ['$' for help]" and any("went away during a motion" in l for l in lines),
      "the next sender is told: %s" % lines)
check(status(port).startswith("<Alarm"), "locked until $X")
port.write(b"$X\n")
check(answer(port) == "ok", "$X unlocks")
port.close()

proc.send_signal(signal.SIGINT)
code = proc.wait(timeout=10)
check(code == 130, "Ctrl-C ends hmc grbl with 130, got %s" % code)
err.seek(0)
print(err.read().strip())

# The same front end on TCP, with --link's name unused: a sender connects, moves, leaves.
terr = open(os.path.join(work, "tcp.err"), "w+")
tcp = subprocess.Popen([hmc, "--port", "sim://grbltcp?fast&fresh&nosave", "grbl", "--tcp", "127.0.0.1:0"],
                       stderr=terr, stdout=subprocess.DEVNULL, env=env)
address = None
for _ in range(500):
    terr.seek(0)
    m = re.search(r"listening on tcp://127\.0\.0\.1:(\d+)", terr.read())
    if m:
        address = int(m.group(1))
        break
    time.sleep(0.02)
check(address is not None, "hmc grbl --tcp prints its address")
if address:
    import socket
    with socket.create_connection(("127.0.0.1", address)) as c:
        c.settimeout(10)
        got = b""
        while b"for help]" not in got:
            got += c.recv(256)
        c.sendall(b"G1 X2 F600\n?")
        while b"ok\r\n" not in got or not re.search(rb"<\w+\|", got):
            got += c.recv(256)
        check(b"\r\nGrbl 1.1h ['$' for help]\r\n" in got and b"ok\r\n" in got, "TCP: banner and ok: %r" % got)
    time.sleep(0.3)
    check(tcp.poll() is None, "hmc grbl --tcp goes on after its sender left")
    tcp.send_signal(signal.SIGINT)
    check(tcp.wait(timeout=10) == 130, "hmc grbl --tcp ends with 130 on Ctrl-C")
# A board of its own (hmc-sim on TCP): switches pressed during moves.
serr = open(os.path.join(work, "sim.err"), "w+")
board = subprocess.Popen([sim, "--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0", "--no-self-test"],
                         stderr=serr, stdout=subprocess.DEVNULL)
ports = []
for _ in range(500):
    serr.seek(0)
    ports = re.findall(r"listening on tcp://127\.0\.0\.1:(\d+)", serr.read())
    if len(ports) == 2:
        break
    time.sleep(0.02)


def control(command):
    import socket
    with socket.create_connection(("127.0.0.1", int(ports[1]))) as c:
        c.sendall((command + "\n").encode())
        return c.recv(4096).decode().strip()


gerr = open(os.path.join(work, "board.err"), "w+")
front = subprocess.Popen([hmc, "--port", "tcp://127.0.0.1:" + ports[0], "grbl", "--pty"], stderr=gerr,
                         stdout=subprocess.DEVNULL, env=env)
path = None
for _ in range(500):
    gerr.seek(0)
    m = re.search(r"hmc grbl: pty (\S+)", gerr.read())
    if m:
        path = m.group(1)
        break
    time.sleep(0.02)
port = serial.Serial(path, 115200, timeout=0.05)
read_line(port), read_line(port)


def alarm_during(move, inject):
    port.write((move + "\n").encode())
    check(answer(port) == "ok", move + " taken")
    running, end = "", time.time() + 10
    while time.time() < end and not running.startswith("<Run"):
        running = status(port)
    check(running.startswith("<Run"), move + " runs: " + running)
    check(control(inject) == "ok", inject)
    lines = []
    end = time.time() + 10
    while time.time() < end and not any(l.startswith("ALARM:") for l in lines):
        lines.append(read_line(port))
    lines += [read_line(port)]  # its [MSG:]
    return lines


lines = alarm_during("G1 X50 F600", "press 1 1")
check("ALARM:1" in lines and any("limit switch" in l for l in lines), "a limit switch during a move: ALARM:1 %s" % lines)
check(status(port).startswith("<Alarm"), "Alarm after the limit switch")
control("auto 1 1")
port.write(b"$X\n")
check(answer(port) == "ok", "$X after the limit alarm")
lines = alarm_during("G1 X-50 F600", "estop")
check("ALARM:3" in lines and any("emergency" in l for l in lines), "the emergency switch during a move: ALARM:3 %s" % lines)
msgs = []
port.write(b"$X\n")
check(answer(port, msgs) == "error:9", "$X refused while the emergency switch is pressed %s" % msgs)
control("estop release")
released, end = [], time.time() + 10
while time.time() < end and not any("released" in l for l in released):
    released.append(read_line(port))
check(any("emergency switch was released" in l for l in released), "the release is told: %s" % released)
port.write(b"$X\n")
check(answer(port) == "ok", "$X once released")
state = json.loads(control("status"))
check(all(m["state"] == "idle" for m in state["motors"]), "every motor at rest: %s" % state["motors"])
port.close()
front.send_signal(signal.SIGINT)
check(front.wait(timeout=10) == 130, "hmc grbl on hmc-sim ends with 130")
gerr.seek(0)
check("link watchdog" not in gerr.read(), "the watchdog armed without a note")
board.send_signal(signal.SIGTERM)
board.wait(timeout=10)

if failures:
    print("grbl_test: %d failures" % len(failures))
    sys.exit(1)
print("grbl_test: ok")
