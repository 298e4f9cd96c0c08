# Every Board method against sim://, the simulated board in this process (fast virtual time).
import os
import warnings

import pytest

import hmc


def test_the_issue_example(sim_url):
    b = hmc.open(sim_url())
    b.move(1, steps=3200, accel=8000, wait=True)
    assert b.status().motors[0].position == 3200
    b.close()


def test_board_properties(sim_url):
    with hmc.open(sim_url()) as b:
        assert b.description.startswith("simulated board sim://")
        assert b.firmware == "0.1.0" and b.protocol >= 6
        assert hmc.__version__.count(".") == 2
        assert b.simulated and not b.watchdog_armed and not b.closed
        assert b.axes == []
        assert "hmc.Board" in repr(b)
    assert b.closed
    with pytest.raises(hmc.Error, match="closed"):
        b.status()


def test_move_in_steps_and_the_motor_record(sim_url):
    with hmc.open(sim_url()) as b:
        m = b.move(3, steps=-1600, speed=4000)
        assert (m.motor, m.state, m.position, m.last_end) == (3, "idle", -1600, "completed")
        assert m.board_position == -1600 * 16 and m.microstep == 16
        assert m.axis is None and m.units is None
        again = b.move("3", by=800)  # a bare number on a motor without a profile axis: steps
        assert again.position == -800
        assert b.move(3, to=hmc.steps(0)).position == 0
        assert b.move(3, to="90deg").position == 800  # any motor takes deg: 200 full steps a turn


def test_move_arguments_are_checked(sim_url):
    with hmc.open(sim_url()) as b:
        with pytest.raises(hmc.InvalidCommand, match="once"):
            b.move(1, to=10, by=10)
        with pytest.raises(hmc.InvalidCommand, match="once"):
            b.move(1)
        with pytest.raises(hmc.InvalidCommand, match="motor must be 1-3"):
            b.move(4, steps=1)
        with pytest.raises(hmc.InvalidCommand, match="no axis 'slide'"):
            b.move("slide", steps=1)
        with pytest.raises(TypeError):
            b.move(1, steps=1.5)
        with pytest.raises(TypeError):
            b.move(1, to=[1])
        with pytest.raises(hmc.InvalidCommand, match="speed"):
            b.move(1, by=10, speed="10mm/s")  # motor 1 has no profile axis: no mm


def test_profile_axes_in_units_end_to_end(sim_url, examples):
    """Home, move in the axis's units, LEDs and status: the maker's whole script."""
    import pathlib

    with hmc.open(sim_url(), profile=pathlib.Path(examples) / "camera-slider.toml") as b:
        assert b.axes == ["slide"]
        b.home("slide")
        st = b.status().motors[0]
        assert st.homed and st.axis == "slide" and st.unit == "mm" and st.units == 0
        m = b.move("slide", to=hmc.mm(250))
        assert m.units == pytest.approx(250) and m.position == 20000
        m = b.move("slide", by="-12.5mm", speed=hmc.mm(40).per_s(), accel="400mm/s2")
        assert m.units == pytest.approx(237.5)
        assert b.move("slide", to=100).units == pytest.approx(100)  # a bare number: the axis's mm
        with pytest.raises(hmc.InvalidCommand, match="linear"):
            b.move("slide", to=hmc.deg(10))
        with pytest.raises(hmc.Refused, match="soft limits") as beyond:
            b.move("slide", to="400mm")
        assert beyond.value.by_board is False and beyond.value.offset is None
        b.led(1, "#ff800010")
        b.led(2, (0, 0, 255))
        b.servo(1, 135)
        s = b.status()
        assert s.strips[0].colour == "#ff800010" and (s.strips[1].b, s.strips[1].w) == (255, 0)
        assert s.servos[0].pulse_us > 0 and s.servos[1].pulse_us == 0
        assert s.firmware == "v2" and s.reported and not s.emergency
        assert s.last_reset == "power-on"
        assert [m.motor for m in s.motors] == [1, 2, 3]
        assert s.motors[0].units == pytest.approx(100)


def test_rounding_is_said(sim_url, examples):
    with hmc.open(sim_url(), profile=os.path.join(examples, "pan-tilt-head.toml")) as b:
        b.zero("pan")
        with pytest.warns(hmc.RoundingWarning, match="rounded to 27"):
            b.move("pan", to=hmc.deg(1))


def test_zero(sim_url):
    with hmc.open(sim_url()) as b:
        b.move(3, steps=500)
        m = b.zero(3)
        assert m.position == 0 and m.homed
        assert b.zero(3, 1000).position == 1000
        assert b.zero(3, "-90deg").position == -800


def test_run_stop_and_wait(sim_url):
    with hmc.open(sim_url()) as b:
        b.run(3, 2000)
        assert b.status().motors[2].endless
        b.stop(3)
        assert b.status().motors[2].state == "idle"
        b.run(2, -1000, accel=4000)
        b.stop()
        assert all(m.state == "idle" for m in b.status().motors)
        before = b.status().motors[2].position
        b.move(3, steps=400, wait=False)
        b.wait(3)
        assert b.status().motors[2].position == before + 400
        b.move(3, steps=400, wait=False)
        b.wait()
        with pytest.raises(hmc.InvalidCommand, match="0"):
            b.run(3, 0)


def test_wait_with_a_timeout_is_no_reply_and_stops(sim_url):
    with hmc.open(sim_url()) as b:
        b.run(3, 1000)
        with pytest.raises(hmc.NoReply) as late:
            b.wait(3, timeout=0.2)
        assert isinstance(late.value, TimeoutError)
        assert b.status().motors[2].state == "idle"


def test_leaving_the_block_stops_what_it_started(sim_url):
    url = sim_url()
    name = url.split("?")[0]
    with hmc.open(url) as b:
        b.run(3, 1000)
        b.run(2, 1000, keep_running=True)
    with hmc.open(name + "?fast") as b:  # the same board, powered on
        motors = b.status().motors
        assert motors[2].state == "idle"
        assert motors[1].state == "moving" and motors[1].endless
        b.stop()


def test_a_board_collected_without_close_stops_what_it_started(sim_url):
    import gc

    url = sim_url()
    b = hmc.open(url)
    b.run(3, 1000)
    del b
    gc.collect()
    with hmc.open(url.split("?")[0] + "?fast") as again:
        assert again.status().motors[2].state == "idle"


def test_a_move_that_ends_early(sim_url):
    with hmc.open(sim_url()) as b:
        # Motor 1 starts mid-travel, 12800 steps (at 1/16) from its reverse switch.
        with pytest.raises(hmc.MotionEndedEarly) as early:
            b.move(1, steps=-20000, speed=20000)
        e = early.value
        assert (e.motor, e.how) == (1, "limit") and e.position == -12800
        assert e.status.switch_reverse
        with pytest.raises(hmc.Refused) as pressed:
            b.move(1, steps=-10)
        assert pressed.value.reason == "limit_pressed" and not pressed.value.by_board


def test_home_all_and_home_without_a_switch(sim_url):
    with hmc.open(sim_url()) as b:
        b.home()
        s = b.status()
        assert s.motors[0].homed and s.motors[1].homed and not s.motors[2].homed
        homed = [(e.motor, e.homed, e.position) for e in b.events(timeout=0) if e.kind == "homed"]
        assert homed == [(1, True, 0), (2, True, 0)]
        with pytest.raises(hmc.Refused) as refused:
            b.home(3)
        assert refused.value.reason == "no_switch"


def test_servo_and_led_refusals(sim_url):
    with hmc.open(sim_url()) as b:
        with pytest.raises(hmc.InvalidCommand) as bad:
            b.servo(1, 200)
        assert bad.value.reason == "out_of_range"
        with pytest.raises(hmc.InvalidCommand, match="colour"):
            b.led(1, "#12")
        with pytest.raises(hmc.InvalidCommand, match="0-255"):
            b.led(1, (1, 2, 300))
        with pytest.raises(TypeError):
            b.led(1, 7)
        b.led(1, "off")


def test_send_and_a_refusal_by_the_board(sim_url):
    with hmc.open(sim_url()) as b:
        reply = b.send("VER")
        assert reply.name == "VER" and reply.values["protocol"] == b.protocol
        assert b.step_budgets() == (reply.values["max_rate"], reply.values["max_ramping_rate"])
        assert b.send("STA 4").name == "STB"
        with pytest.raises(hmc.Refused) as nak:
            b.send("STX#6#STM#3#1#1#11#1000#238#ETX", raw=True)
        e = nak.value
        assert e.by_board and (e.reason, e.code, e.token, e.offset) == ("checksum_mismatch", 8, 8, 24)
        with pytest.raises(hmc.FrameError):
            b.send("STM 1 1 3 1000 500")


def test_seed_firmware_is_too_old(sim_url):
    with hmc.open(sim_url("seed")) as b:
        assert b.firmware == "seed" and b.protocol is None
        with pytest.raises(hmc.FirmwareTooOld, match="reflash"):
            b.zero(3)
        with pytest.raises(hmc.FirmwareTooOld, match="max_ramping_rate.*needs protocol 7"):
            b.step_budgets()
        with pytest.raises(hmc.Refused, match="acceleration"):
            b.move(3, steps=100, accel=1000)
        assert not b.status().reported


def test_events_iterator_and_callbacks(sim_url):
    with hmc.open(sim_url()) as b:
        seen = []
        b.on_event(seen.append)
        b.move(3, steps=200)
        done = [e for e in seen if e.kind == "move_done"]
        assert done and done[-1].motor == 3 and done[-1].how == "completed" and done[-1].position == 200
        events = list(b.events(timeout=0.05))
        assert [e.kind for e in events if e.kind == "move_done"] == ["move_done"]
        assert events[-1].line.startswith("STX#") and events[-1].time > 0
        b.move(3, steps=100, wait=False)
        first = next(iter(b.events(timeout=5)))
        assert first.kind == "move_done"
        with pytest.raises(TypeError):
            b.on_event(3)


def test_a_callback_that_raises_stops_the_motors(sim_url):
    with hmc.open(sim_url()) as b:
        raised = []

        def stop_at_limit(event):
            if not raised:
                raised.append(event)
                raise RuntimeError("seen " + event.kind)

        b.run(3, 500)
        b.move(2, steps=20, wait=False)
        b.on_event(stop_at_limit)
        with pytest.raises(RuntimeError, match="seen move_done"):
            b.wait(2)
        assert all(m.state == "idle" for m in b.status().motors)


def test_a_callback_may_not_call_the_board(sim_url):
    with hmc.open(sim_url()) as b:
        b.on_event(lambda event: b.status())
        with pytest.raises(RuntimeError, match="callback cannot call the board"):
            b.move(3, steps=100)


def test_run_file_with_progress(sim_url, examples):
    with hmc.open(sim_url()) as b:
        progress = []
        done = b.run_file(os.path.join(examples, "camera-slider.json"), progress=progress.append)
        assert done == len(hmc.plan(os.path.join(examples, "camera-slider.json")).actions)
        assert progress[0].kind == "started" and progress[0].step == 1 and progress[-1].kind == "done"
        assert progress[-1].step == progress[-1].total
        assert b.run_file(os.path.join(examples, "camera-slider.json"), start_at=done) == 1
        with pytest.raises(hmc.InvalidCommand, match="only"):
            b.run_file(os.path.join(examples, "camera-slider.json"), start_at=99)


def test_run_file_resumes_where_the_plan_has_the_motors(sim_url, examples):
    path = os.path.join(examples, "camera-slider.json")
    plan = hmc.plan(path)
    glide_out = next(a.index for a in plan.actions if a.description == "glide out")
    with hmc.open(sim_url()) as b:
        progress = []
        # The file first started with motor 3 at 0; resume after its glide out of 4 turns.
        done = b.run_file(path, start_at=glide_out + 1, at=(None, None, 0), progress=progress.append)
        assert done == len(plan.actions) - glide_out
        assert progress[0].kind == "returning"
        assert b.status().motors[2].position == 0  # back from 12800 (4 turns at 1/16) to where it began


def test_run_file_refuses_a_file_with_mistakes(sim_url, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"hmc_motion": 1, "motors": {}, "steps": [{"servo": {"id": 3, "angle": 90}}]}')
    with hmc.open(sim_url()) as b:
        with pytest.raises(hmc.MotionFileError) as refused:
            b.run_file(str(bad))
        assert refused.value.errors[0].line == 1


def test_a_progress_callback_that_raises_stops_the_run(sim_url, examples):
    with hmc.open(sim_url()) as b:
        def give_up(p):
            if p.step == 2:
                raise KeyError("enough")

        with pytest.raises(KeyError):
            b.run_file(os.path.join(examples, "camera-slider.json"), progress=give_up)
        assert all(m.state == "idle" for m in b.status().motors)


def test_port_and_profile_errors(tmp_path):
    with pytest.raises(hmc.PortError, match="ttyNOPE"):
        hmc.open("/dev/ttyNOPE")
    with pytest.raises(hmc.PortError, match="unknown"):
        hmc.open("sim://x?bogus")
    bad = tmp_path / "bad.toml"
    bad.write_text("[axis.slide]\nmotor = 7\nspead = 3\n")
    with pytest.raises(hmc.ProfileError) as mistakes:
        hmc.open("sim://x", profile=str(bad))
    lines = [m[0] for m in mistakes.value.mistakes]
    assert 2 in lines and 3 in lines and "spead" in str(mistakes.value)
    with pytest.raises(hmc.PortError):
        hmc.open("sim://x", profile=str(tmp_path / "none.toml"))
    with pytest.raises(hmc.InvalidCommand):
        hmc.open("sim://x", firmware="v9")


def test_threads_share_a_board(sim_url):
    import threading

    with hmc.open(sim_url()) as b:
        errors = []

        def mover(motor):
            try:
                for _ in range(3):
                    b.move(motor, steps=100)
            except Exception as e:  # noqa: BLE001 - collected for the assertion
                errors.append(e)

        threads = [threading.Thread(target=mover, args=(m,)) for m in (2, 3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not errors
        assert [m.position for m in b.status().motors[1:]] == [300, 300]


def test_a_motion_file_in_the_boards_profile(sim_url, examples, tmp_path):
    """A file that names no profile and declares no motors is read in the board's (or check's) profile."""
    slider = os.path.join(examples, "camera-slider.toml")
    glide = tmp_path / "glide.json"
    glide.write_text('{"hmc_motion": 1, "steps": [{"home": "slide"},'
                     ' {"move": {"motor": "slide", "to": {"mm": 100}, "speed": {"mm_per_s": 100}}}]}')
    assert len(hmc.check(glide, profile=slider).actions) == 2
    glide.write_text(glide.read_text().replace('"mm": 100', '"mm": 12.3456'))
    with pytest.warns(hmc.RoundingWarning, match="12.3456 mm is 987.648 steps: rounded to 988"):
        hmc.plan(glide, profile=slider)
    with pytest.raises(hmc.MotionFileError):
        hmc.check(glide)  # no motors, no profile
    with pytest.raises(hmc.ProfileError):
        hmc.plan(glide, profile=tmp_path / "glide.json")
    with hmc.open(sim_url(), profile=slider) as b:
        with pytest.warns(hmc.RoundingWarning):
            assert b.run_file(glide) == 2
        assert b.status().motors[0].position == 988
    # A file written for another rig is refused in the profile given, naming both.
    with pytest.raises(hmc.MotionFileError, match="written for the profile .*camera-slider.toml, not for .*pan-tilt-head.toml"):
        hmc.check(os.path.join(examples, "camera-slider-mm.json"), profile=os.path.join(examples, "pan-tilt-head.toml"))
