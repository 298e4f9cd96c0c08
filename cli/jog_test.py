#!/usr/bin/python3
"""`hmc jog` through a pseudo-terminal against hmc-sim over TCP (with its trace): keys in, the
board's frames out (STM lines and their step counts), a soft limit respected, z zeroing (POS),
the terminal's modes put back after q, SIGTERM, Ctrl-C (a byte in raw mode) and a lost link,
every motor stopped on exit (and no stop claimed when the link is gone), the watchdog armed, and a
refusal when standard input is not a terminal.

Usage: jog_test.py HMC HMC_SIM
"""
import atexit, json, os, re, select, shutil, signal, subprocess, sys, tempfile, termios, time

hmc, sim = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
work = tempfile.mkdtemp(prefix="hmc-jog-")
atexit.register(shutil.rmtree, work, True)
trace = os.path.join(work, "trace.jsonl")
failures = 0
env = dict(os.environ, HMC_SIM_STATE=os.path.join(work, "state"), XDG_CONFIG_HOME=work)
env.pop("HMC_PORT", None)
env.pop("HMC_PROFILE", None)

# A linear axis of 80 steps per mm (200 x 1/16 steps a turn, 40 mm a turn), slow enough that a
# jog is still under way when the test interrupts it; motors 2 and 3 stay bare motors (steps).
profile = os.path.join(work, "jog.toml")
with open(profile, "w") as f:
    f.write('[axis.slide]\nmotor = 1\nsteps_per_rev = 200\nmicrostep = 16\nmm_per_rev = "40mm"\n'
            'limits = ["-50mm", "5mm"]\nspeed = "5mm/s"\n')


def check(ok, what):
    global failures
    if not ok:
        failures += 1
    print(("ok   " if ok else "FAIL ") + what)
    return ok


# Standard input not a terminal: refused with exit 2 before any port is opened.
r = subprocess.run([hmc, "--port", "tcp://127.0.0.1:1", "jog"], stdin=subprocess.DEVNULL,
                   capture_output=True, text=True, env=env, timeout=10)
check(r.returncode == 2 and "not" in r.stderr and "terminal" in r.stderr,
      "jog without a terminal: exit 2 (%d) %r" % (r.returncode, r.stderr.strip()))

serr = open(os.path.join(work, "sim.err"), "w+")
board = subprocess.Popen([sim, "--tcp", "127.0.0.1:0", "--no-self-test", "--trace", trace],
                         stderr=serr, stdout=subprocess.DEVNULL)
atexit.register(lambda: board.poll() is None and board.kill())
port = None
for _ in range(200):
    serr.seek(0)
    m = re.search(r"tcp://127\.0\.0\.1:(\d+)", serr.read())
    if m:
        port = "tcp://127.0.0.1:" + m.group(1)
        break
    time.sleep(0.02)
if not port:
    print("FAIL hmc-sim did not start")
    sys.exit(1)


class Jog:
    """`hmc jog` on a new pseudo-terminal; `screen` is everything it wrote there."""

    def __init__(self):
        self.master, self.slave = os.openpty()
        self.modes = termios.tcgetattr(self.slave)
        self.err = open(os.path.join(work, "jog.err"), "w+")
        self.proc = subprocess.Popen([hmc, "--profile", profile, "--port", port, "jog"], stdin=self.slave,
                                     stdout=self.slave, stderr=self.err, env=env, start_new_session=True)
        self.screen = ""

    def read(self, seconds):
        end = time.time() + seconds
        while time.time() < end:
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if ready:
                try:
                    self.screen += os.read(self.master, 4096).decode(errors="replace")
                except OSError:
                    return

    def status(self):
        """The status line as last drawn."""
        return self.screen.split("\x1b[K")[-1].split("\r")[0].split("\n")[0]

    def wait_for(self, pattern, seconds=5):
        end = time.time() + seconds
        while time.time() < end:
            self.read(0.05)
            if re.search(pattern, self.status()):
                return True
        print("     status line: %r" % self.status())
        return False

    def keys(self, text):
        os.write(self.master, text.encode())

    def restored(self):
        return termios.tcgetattr(self.slave) == self.modes

    def close(self):
        os.close(self.master)
        os.close(self.slave)


def rx_lines(command):
    with open(trace) as f:
        events = [json.loads(l) for l in f if l.strip()]
    return [e["line"].split("#")[3:-2] for e in events if e.get("ev") == "rx" and ("#%s#" % command) in e["line"]]


def board_status():
    r = subprocess.run([hmc, "--port", port, "status", "--json"], capture_output=True, text=True, env=env, timeout=10)
    return json.loads(r.stdout)


start = time.time()
j = Jog()
check(j.wait_for(r"slide 0 mm.*step 1 mm"), "jog starts: the status line shows slide 0 mm, step 1 mm")
check(not j.restored(), "the terminal is in raw mode while jogging")
j.keys("z")
check(j.wait_for(r"slide zeroed"), "z zeroes the first axis")
check(any(l[0] == "1" for l in rx_lines("POS")), "z sent POS for motor 1: %s" % rx_lines("POS"))
j.keys("\x1b[C")  # Right: +1 mm
check(j.wait_for(r"slide 1 mm", 5), "Right moves slide by 1 mm")
stm = rx_lines("STM")
check(stm and stm[-1][0] == "1" and stm[-1][3] == "80", "Right: STM for motor 1, 80 steps: %s" % stm[-1:])
j.keys("\x1b[1;2C")  # Shift+Right: +10 mm, beyond the 5 mm limit
check(j.wait_for(r"soft limit 5 mm", 3), "Shift+Right stops at the soft limit, said on the status line")
check(j.wait_for(r"slide 5 mm", 5), "slide at 5 mm, not 11 mm")
stm = rx_lines("STM")
check(stm[-1][0] == "1" and stm[-1][3] == "320", "Shift+Right: 320 steps (4 mm), not 800: %s" % stm[-1:])
j.keys("\x1b[A")  # Up: motor 2, 10 steps at the middle step size
check(j.wait_for(r"motor 2 10 steps"), "Up moves motor 2 by 10 steps")
j.keys("+\x1b[A")  # step 100: motor 2 at 110
check(j.wait_for(r"motor 2 110 steps.*step 100 steps"), "+ makes the step 100 steps")
j.keys("\x1b[6~")  # Page Down: motor 3, -100 steps
check(j.wait_for(r"motor 3 -100 steps"), "Page Down moves motor 3 back 100 steps")
stm = rx_lines("STM")
check([l[0] for l in stm[-3:]] == ["2", "2", "3"] and [l[3] for l in stm[-3:]] == ["10", "100", "100"],
      "Up, Up, Page Down: STM for 2, 2, 3 with 10, 100, 100 steps: %s" % stm[-3:])
j.keys("q")
try:
    code = j.proc.wait(timeout=5)
except subprocess.TimeoutExpired:
    j.proc.kill()
    code = None
check(code == 0, "q quits with exit 0 (%s)" % code)
check(j.restored(), "after q the terminal's modes are the ones it had")
j.err.seek(0)
check("every motor was sent a stop" in j.err.read(), "q: every motor sent a stop")
j.close()

# SIGTERM in the middle of a jog: 10 mm at 5 mm/s takes 2 s.
j = Jog()
check(j.wait_for(r"slide 5 mm"), "a second jog sees slide at 5 mm")
j.keys("++\x1b[D")  # step 10 mm, Left: to -5 mm
time.sleep(0.6)
j.read(0.1)
before = len(rx_lines("STM"))
j.proc.send_signal(signal.SIGTERM)
try:
    code = j.proc.wait(timeout=5)
except subprocess.TimeoutExpired:
    j.proc.kill()
    code = None
check(code == 130, "SIGTERM mid-jog: exit 130 (%s)" % code)
check(j.restored(), "after SIGTERM the terminal's modes are the ones it had")
stm = rx_lines("STM")
check(["1", "0"] in [l[:2] for l in stm[before:]] and stm[before - 1][:2] == ["1", "2"],
      "SIGTERM: hmc sent a stop to motor 1 after its jog back: %s" % stm[before - 1:])
motors = board_status().get("motors", [])
check(motors and all(m.get("state") == "idle" for m in motors), "every motor at rest after SIGTERM")
p = next((m for m in motors if m.get("motor") == 1), {})
check(bool(p) and -400 < p.get("steps", -400) < 400, "slide stopped partway between 5 mm and -5 mm: %s steps" % p.get("steps"))
j.close()

check(any(l[0] != "0" for l in rx_lines("WDG")), "the jog armed the link watchdog: %s" % rx_lines("WDG")[:1])

# Ctrl-C arrives as a byte in raw mode: exit 130, the terminal put back, the motors stopped.
j = Jog()
check(j.wait_for(r"slide"), "a third jog starts")
before = len(rx_lines("STM"))
j.keys("\x03")
try:
    code = j.proc.wait(timeout=5)
except subprocess.TimeoutExpired:
    j.proc.kill()
    code = None
check(code == 130, "Ctrl-C: exit 130 (%s)" % code)
check(j.restored(), "after Ctrl-C the terminal's modes are the ones it had")
check(sum(1 for l in rx_lines("STM")[before:] if l[1] == "0") == 3, "Ctrl-C: a stop for each motor")
j.close()

# The link lost mid-jog (the board gone): an error, the terminal put back.
j = Jog()
check(j.wait_for(r"slide"), "a fourth jog starts")
j.keys("\x1b[1;2D")
time.sleep(0.3)
board.kill()
board.wait(timeout=5)
try:
    code = j.proc.wait(timeout=10)
except subprocess.TimeoutExpired:
    j.proc.kill()
    code = None
j.err.seek(0)
said = j.err.read()
check(code in (3, 4), "the link lost: exit 3 or 4 (%s) %r" % (code, said.strip()[-160:]))
check("every motor was sent a stop" not in said and "link watchdog stops the motors" in said,
      "the link lost: no stop claimed, the watchdog named")
check(j.restored(), "after the link is lost the terminal's modes are the ones it had")
j.close()
elapsed = time.time() - start
if failures:
    print("jog_test: %d failures (%.1f s)" % (failures, elapsed))
    sys.exit(1)
print("jog_test: all checks passed (%.1f s)" % elapsed)
