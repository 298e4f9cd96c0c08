# Ctrl-C during a wait: SIGINT sent to a child interpreter running the wait (not to pytest).
# The wait must end within a few tens of milliseconds with KeyboardInterrupt, every motor stopped
# first, as the board itself says.
import json
import os
import signal
import time

from conftest import run_python

CHILD = r"""
import sys, hmc
b = hmc.open(sys.argv[1])
what = sys.argv[2]
if what == "wait":
    b.run(3, 1000)
print("ready", flush=True)
try:
    if what == "wait":
        b.wait(3)
    elif what == "move":
        b.move(2, steps=100000, speed=1000)
    elif what == "run_file":
        b.run_file(sys.argv[3])
    elif what == "events":
        for e in b.events():
            pass
except KeyboardInterrupt:
    print("interrupted", flush=True)
    print("states", ",".join(m.state for m in b.status().motors), flush=True)
    raise
"""


def interrupt(port, what, *extra, after=0.4):
    import subprocess

    child = run_python(CHILD, port, what, *extra, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "ready"
    time.sleep(after)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=20)
    return child.returncode, out, err, time.monotonic() - sent


def test_ctrl_c_during_wait_stops_every_motor(sim_server):
    server = sim_server()
    code, out, err, took = interrupt(server.url, "wait")
    assert code != 0 and "KeyboardInterrupt" in err
    assert "interrupted" in out and "states idle,idle,idle" in out, (out, err)
    assert json.loads(server.control("status"))["motors"][2]["state"] == "idle"
    assert took < 5


def test_ctrl_c_during_a_move_on_the_simulated_board(sim_url):
    url = sim_url().replace("fast&", "")  # real time
    code, out, err, _ = interrupt(url, "move")
    assert "interrupted" in out and "states idle,idle,idle" in out, (out, err)


def test_ctrl_c_during_a_motion_file(sim_server, examples):
    server = sim_server()
    code, out, err, _ = interrupt(server.url, "run_file", os.path.join(examples, "camera-slider.json"), after=1.0)
    assert "interrupted" in out and "states idle,idle,idle" in out, (out, err)
    assert all(m["state"] == "idle" for m in json.loads(server.control("status"))["motors"])


def test_ctrl_c_while_iterating_events(sim_server):
    server = sim_server()
    code, out, err, took = interrupt(server.url, "events")
    assert "interrupted" in out and took < 5, (out, err)
