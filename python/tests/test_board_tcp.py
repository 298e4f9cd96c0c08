# Against hmc-sim over TCP (another process, real time): the link watchdog kept alive, switches
# and the emergency switch from its control channel, a lost link, a silent port.
import json
import socket
import threading
import time

import pytest

import hmc


def motor_state(server, motor):
    return json.loads(server.control("status"))["motors"][motor - 1]["state"]


def test_watchdog_is_armed_and_kept_alive_while_the_script_sleeps(sim_server):
    server = sim_server()
    with hmc.open(server.url, watchdog=0.3) as b:
        assert b.watchdog_armed and not b.simulated
        assert b.description.startswith("tcp 127.0.0.1")
        b.run(3, 1000)
        time.sleep(1.0)  # no board call for over three timeouts: the library keeps the link alive
        s = b.status()
        assert s.watchdog_ms == 300 and not s.watchdog_fired
        assert s.motors[2].state == "moving"
        b.disarm_watchdog()
        assert not b.watchdog_armed
    assert motor_state(server, 3) == "idle"  # leaving the block stopped it


def test_no_watchdog_when_asked(sim_server):
    server = sim_server()
    with hmc.open(server.url, watchdog=0) as b:
        assert not b.watchdog_armed
        b.arm_watchdog(0.5)
        assert b.watchdog_armed
        with pytest.raises(hmc.InvalidCommand):
            b.arm_watchdog(0)


def test_the_emergency_switch_ends_a_move_early(sim_server):
    server = sim_server()
    with hmc.open(server.url) as b:
        def press_once_moving():
            deadline = time.monotonic() + 20
            while motor_state(server, 3) != "moving" and time.monotonic() < deadline:
                time.sleep(0.02)
            server.control("estop")

        presser = threading.Thread(target=press_once_moving)
        presser.start()
        with pytest.raises(hmc.MotionEndedEarly) as early:
            b.move(3, steps=100000, speed=2000)
        presser.join()
        assert early.value.how == "emergency" and early.value.motor == 3
        assert 0 < early.value.position < 100000
        with pytest.raises(hmc.Refused) as refused:
            b.move(3, steps=10)
        assert refused.value.reason == "emergency_stop"
        assert server.control("estop release") == "ok"
        kinds = [e.kind for e in b.events(timeout=0.5)]
        assert "emergency" in kinds


def test_switch_events(sim_server):
    server = sim_server()
    with hmc.open(server.url) as b:
        list(b.events(timeout=0.1))  # what came before
        assert server.control("press 2 1") == "ok"
        limit = next(e for e in b.events(timeout=2) if e.kind == "limit")
        assert (limit.motor, limit.end, limit.pressed) == (2, 1, True)
        assert b.status().motors[1].switch_forward


def test_a_lost_link_during_a_wait(sim_server):
    server = sim_server()
    with hmc.open(server.url) as b:
        b.run(3, 1000)
        threading.Timer(0.3, server.process.kill).start()
        with pytest.raises(hmc.LinkLost) as lost:
            b.wait(3)
        assert isinstance(lost.value, ConnectionError)
    assert b.closed


def test_a_silent_port_is_no_reply():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    port = listener.getsockname()[1]
    try:
        with pytest.raises(hmc.NoReply, match="no reply to VER"):
            hmc.open(f"tcp://127.0.0.1:{port}", timeout=0.3)
    finally:
        listener.close()


def test_a_closed_port_is_a_port_error():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    listener.close()
    with pytest.raises(hmc.PortError):
        hmc.open(f"tcp://127.0.0.1:{port}")


def test_the_link_watchdog_event(sim_server):
    """A watchdog armed behind the library's back (no keep-alive) fires: an event and a status."""
    server = sim_server()
    with hmc.open(server.url, watchdog=0) as b:
        b.run(3, 1000)
        b.send("WDG 100")
        time.sleep(0.4)
        fired = [e for e in b.events(timeout=0.5) if e.kind == "watchdog"]
        assert fired and fired[0].motor == 3 and fired[0].how == "watchdog"
        s = b.status()
        assert s.watchdog_fired and s.motors[2].state == "idle"
