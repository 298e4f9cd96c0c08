#!/usr/bin/python3
"""Runs every cell of cli/testdata/lies.txt: the real `hmc` against a fresh hmc-sim (or a port
that never answers), the failure the cell names injected while the command runs, and checks the
exit code, the wording and the board's state afterwards (hmc-sim's control channel).
Usage: lies_test.py HMC_BINARY HMC_SIM_BINARY SOURCE_DIR"""
import json, os, pty, re, shlex, signal, socket, subprocess, sys, tempfile, threading, time

hmc, sim, src = (os.path.abspath(a) for a in sys.argv[1:4])
work = tempfile.mkdtemp()
env = dict(os.environ, HMC_SIM_STATE=os.path.join(work, "state"))
env.pop("HMC_PORT", None)


def start_sim(extra):
    err = open(os.path.join(work, "sim.err"), "w+")
    proc = subprocess.Popen([sim, "--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0", "--no-self-test"] + extra,
                            stderr=err, stdout=subprocess.DEVNULL)
    for _ in range(200):
        err.seek(0)
        text = err.read()
        ports = re.findall(r"listening on tcp://127\.0\.0\.1:(\d+)", text)
        if len(ports) == 2:
            return proc, "tcp://127.0.0.1:" + ports[0], int(ports[1])
        time.sleep(0.02)
    proc.kill()
    raise RuntimeError("hmc-sim did not start: " + text)


def control(port, command):
    with socket.create_connection(("127.0.0.1", port)) as c:
        c.sendall((command + "\n").encode())
        answer = b""
        while not answer.endswith(b"\n"):
            chunk = c.recv(4096)
            if not chunk:
                break
            answer += chunk
    return answer.decode().strip()


def silent_tcp():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    held = []

    def hold():
        try:
            while True:
                held.append(listener.accept())  # kept open, never answered
        except OSError:
            pass  # the listener was closed: the cell is over

    threading.Thread(target=hold, daemon=True).start()
    return listener, "tcp://127.0.0.1:%d" % listener.getsockname()[1]


def run_cell(cell, board, during, args, want_exit, wording, after):
    sim_proc, cport, keep = None, None, None
    if board in ("v2", "seed", "on-switch", "near", "far"):
        extra = {"v2": [], "seed": ["--seed"], "on-switch": ["--axis", "1:0:819200:0"],
                 "near": ["--axis", "1:0:819200:4096"], "far": ["--axis", "1:-2000000:2000000:1000000"]}[board]
        sim_proc, port, cport = start_sim(extra)
    elif board == "sim":
        port = "sim://lies-" + cell
    elif board == "missing-port":
        port = "/dev/hmc-lies-no-such-port"
    elif board == "silent-pty":
        master, slave = pty.openpty()
        port, keep = os.ttyname(slave), (master, slave)
    else:
        keep, port = silent_tcp()
    try:
        cmd = [hmc, "--port", port, "--watchdog", "300"] + [
            a.replace("{testdata}", os.path.join(src, "cli", "testdata")).replace("{src}", src).replace("{nl}", "\n")
            for a in shlex.split(args)]
        if board == "sim":
            cmd[2] += "?fresh"
        # during: "none", or what happens while the command runs ("int@800"), and/or a command
        # run after it on the same board ("then:status"), whose exit and wording are checked.
        inject, then = None, None
        for item in during.split("+"):
            if item.startswith("then:"):
                then = shlex.split(item[len("then:"):])
            elif item != "none":
                inject = item.split("@", 1)
        t0 = time.monotonic()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, cwd=work)
        if inject:
            what, at = inject
            at, _, words = at.partition(":")
            time.sleep(int(at) / 1000)
            if what == "estop":
                control(cport, "estop")
            elif what == "ctl":
                control(cport, words)
            elif what == "simkill":
                sim_proc.kill()
            elif what == "simstop":
                sim_proc.send_signal(signal.SIGSTOP)
            else:
                proc.send_signal({"kill": signal.SIGKILL, "int": signal.SIGINT, "hup": signal.SIGHUP,
                                  "term": signal.SIGTERM}[what])
        out, _ = proc.communicate(timeout=60)
        if inject and inject[0] == "simstop":
            sim_proc.send_signal(signal.SIGCONT)
        code = proc.returncode if proc.returncode >= 0 else 128 - proc.returncode
        text = out.decode(errors="replace")
        if then:
            # The cell checks the command that follows, on the same board.
            nxt = subprocess.run([hmc, "--port", port] + then, stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, env=env, cwd=work, timeout=60)
            code, text = nxt.returncode, text + "\n--- then: " + nxt.stdout.decode(errors="replace")
        problems = []
        if code != int(want_exit):
            problems.append("exit %d, want %s" % (code, want_exit))
        # "A !~ B": A must match and B must not.
        must, _, must_not = wording.partition(" !~ ")
        if not re.search(must, text, re.M):
            problems.append("wording does not match /%s/" % must)
        if must_not and re.search(must_not, text, re.M):
            problems.append("wording matches /%s/, which it must not" % must_not)
        if after in ("idle", "fired"):
            time.sleep(0.6)  # the watchdog's 300 ms and a stop's braking
            status = json.loads(control(cport, "status"))
            moving = [m for m in status["motors"] if m["state"] != "idle"]
            if moving:
                problems.append("motors still moving on the board: %s" % moving)
        if after == "where-said":
            time.sleep(0.6)
            said = 0
            status = json.loads(control(cport, "status"))
            for motor, steps, micro in re.findall(r"motor (\d)[^\n]*? stopped:? at (-?\d+) steps of 1/(\d+)", text):
                said += 1
                board_pos = status["motors"][int(motor) - 1]["pos"]
                if int(steps) * 256 // int(micro) != board_pos or status["motors"][int(motor) - 1]["state"] != "idle":
                    problems.append("motor %s: hmc says %s steps of 1/%s, the board rests at %d/256 (%s)" %
                                    (motor, steps, micro, board_pos, status["motors"][int(motor) - 1]["state"]))
            if not said:
                problems.append("hmc named no position where a motor stopped")
        if after.startswith("moved:"):
            # Each motor named moved on the board (a command the board ignored moves nothing).
            time.sleep(0.3)
            status = json.loads(control(cport, "status"))
            for motor in after[len("moved:"):].split(","):
                m = status["motors"][int(motor) - 1]
                if m["pos"] == 0 or m["state"] != "idle":
                    problems.append("motor %s did not move, or still moves, on the board: %s" % (motor, m))
        if after == "fired":
            st = subprocess.run([hmc, "--port", port, "status", "--json"], capture_output=True, env=env, cwd=work)
            if not json.loads(st.stdout).get("watchdog", {}).get("fired"):
                problems.append("the next status does not report the watchdog: " + st.stdout.decode())
        return problems, text, time.monotonic() - t0
    finally:
        if sim_proc:
            sim_proc.kill()
            sim_proc.wait()
        if isinstance(keep, tuple):
            for fd in keep:
                os.close(fd)
        elif keep is not None:
            keep.close()


failures = 0
cells = 0
start = time.monotonic()
for line in open(os.path.join(src, "cli", "testdata", "lies.txt")).read().splitlines():
    if not line.strip() or line.startswith("#"):
        continue
    fields = [f.strip() for f in line.split(" | ")]
    if not re.search(os.environ.get("LIES_CELLS", ""), fields[0]):
        continue
    cells += 1
    problems, text, took = run_cell(*fields)
    if problems:
        failures += 1
        print("FAIL %s: %s\n  hmc %s\n  output: %s" % (fields[0], "; ".join(problems), fields[3],
                                                      text.strip().replace("\n", "\n          ")))
# docs/cli.md's exit-code table is the contract: each of its codes is some cell's expected exit.
if not os.environ.get("LIES_CELLS"):
    docs = open(os.path.join(src, "docs", "cli.md")).read()
    table = docs.split("## Exit codes", 1)[1].split("\n## ", 1)[0]
    documented = set(re.findall(r"^\| (\d+) \|", table, re.M))
    expected = {l.split(" | ")[4].strip() for l in open(os.path.join(src, "cli", "testdata", "lies.txt")).read().splitlines()
                if l.strip() and not l.startswith("#")}
    for code in sorted(documented - expected, key=int):
        failures += 1
        print("FAIL docs/cli.md's exit code %s has no cell in cli/testdata/lies.txt" % code)
    if len(documented) < 7:
        failures += 1
        print("FAIL docs/cli.md's exit-code table was not found (%s)" % sorted(documented))
print("lies_test: %d cells, %d failed (%.1f s)" % (cells, failures, time.monotonic() - start))
sys.exit(1 if failures else 0)
