# Frames and motion files without a board: encode/decode with the codec's diagnostics, check
# and plan, quantities.
import os

import pytest

import hmc


def test_encode_forms():
    assert hmc.encode("STM", 1, 1, 128, 1000, 500) == "STX#6#STM#1#1#128#1000#500#94#ETX"
    assert hmc.encode("[#SVM#1#135]") == "STX#3#SVM#1#135#136#ETX"
    assert hmc.encode("SVM 1 135") == "STX#3#SVM#1#135#136#ETX"
    assert hmc.encode(" STX#03#SVM#1#10#11#ETX") == "STX#3#SVM#1#10#11#ETX"
    assert hmc.encode("VER", crc=True) == "STX#1#VER#04369#ETX"


def test_encode_refuses_with_the_codecs_diagnostic():
    with pytest.raises(hmc.FrameError) as refused:
        hmc.encode("STM", 1, 1, 3, 1000, 500)
    e = refused.value
    assert (e.reason, e.field, e.found) == ("out_of_range", "microstep", 3)
    assert "power of two" in str(e)
    assert isinstance(e, ValueError) and isinstance(e, hmc.Error)
    with pytest.raises(hmc.FrameError, match="bad_length"):
        hmc.encode("SVM", 1)
    with pytest.raises(TypeError):
        hmc.encode()


def test_decode_explains_where_a_frame_is_wrong():
    with pytest.raises(hmc.FrameError) as refused:
        hmc.decode("STX#6#STM#3#1#1#11#1000#238#ETX")
    e = refused.value
    assert (e.reason, e.code, e.token, e.offset, e.field, e.expected, e.found) == (
        "checksum_mismatch", 8, 8, 24, "checksum", 248, 238)
    assert e.input == "STX#6#STM#3#1#1#11#1000#238#ETX"


def test_decode_gives_values_description_and_canonical_form():
    f = hmc.decode(" STX#03#SVM#1#10#11#ETX")
    assert f.name == "SVM" and f.values == {"servo": 1, "angle": 10}
    assert not f.canonical and f.frame == "STX#3#SVM#1#10#11#ETX"
    assert "servo 1" in f.description
    assert hmc.decode("STX#6#STM#1#1#128#1000#50#156#ETX").warnings  # 50 us is below the advice
    board = hmc.decode("STX#5#EVD#1#2#1#1600#68#ETX", board=True)
    assert board.event and board.name == "EVD" and board.values["how"] == 2
    assert board == hmc.decode("STX#5#EVD#1#2#1#1600#68#ETX", board=True)
    assert "Frame(name='EVD'" in repr(board)


def test_round_trip_every_spec_example(examples):
    for line in open(os.path.join(examples, "spec-frames.txt")):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            decoded = hmc.decode(line)
        except hmc.FrameError:
            continue
        again = hmc.decode(hmc.encode(line))
        assert (again.name, again.values, again.frame) == (decoded.name, decoded.values, decoded.frame)


def test_check_a_motion_file_with_mistakes(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(
        '{\n'
        '  "hmc_motion": 1,\n'
        '  "motors": {"pan": {"motor": 4, "microstep": 3}},\n'
        '  "steps": [\n'
        '    {"move": {"motor": "tilt", "by": {"steps": 100}}},\n'
        '    {"servo": {"id": 1, "angle": 200}}\n'
        '  ]\n'
        '}\n')
    with pytest.raises(hmc.MotionFileError) as refused:
        hmc.check(str(bad))
    errors = refused.value.errors
    assert len(errors) >= 4, errors
    places = {(e.line, e.path) for e in errors}
    assert (3, "$.motors.pan.motor") in places
    assert (3, "$.motors.pan.microstep") in places
    assert any(e.line == 5 and "tilt" in e.message for e in errors)
    assert any(e.line == 6 and e.path.endswith("angle") for e in errors)
    assert all(e.column > 0 for e in errors)
    assert str(errors[0]).startswith(f"{bad}:{errors[0].line}:{errors[0].column}:")
    assert len(str(refused.value).splitlines()) == len(errors)


def test_check_an_unreadable_file():
    with pytest.raises(hmc.MotionFileError, match="nowhere.json"):
        hmc.check("/nowhere.json")


def test_plan_gives_a_timeline_and_velocity_samples(examples):
    import pathlib

    plan = hmc.plan(pathlib.Path(examples, "pan-tilt-scan.json"))
    assert plan.duration_s > 0 and len(plan.actions) > 3
    assert [a.index for a in plan.actions] == list(range(1, len(plan.actions) + 1))
    assert all(a.line > 0 for a in plan.actions)
    track = plan.tracks[0]
    assert len(track.t) == len(track.velocity) > 2
    assert max(abs(v) for v in track.velocity) > 0
    assert plan.svg().startswith("<svg") or "<svg" in plan.svg()[:200]
    assert plan.csv().splitlines()[0] == "t_s,motor,name,velocity"
    assert hmc.check(os.path.join(examples, "pan-tilt-scan.json")).duration_s == plan.duration_s
    seed = hmc.plan(os.path.join(examples, "pan-tilt-scan.json"), firmware="seed")
    assert seed.duration_s > 0


def test_quantities():
    assert str(hmc.mm(250)) == "250mm"
    assert str(hmc.deg(-90)) == "-90deg"
    assert str(hmc.mm(20).per_s()) == "20mm/s"
    assert str(hmc.mm(100).per_s().per_s()) == "100mm/s2"
    assert hmc.quantity("20mm/s") == hmc.mm(20).per_s()
    assert (-hmc.rev(1.5)).value == -1.5
    assert repr(hmc.deg(45)) == "hmc.deg(45)"
    with pytest.raises(hmc.InvalidCommand):
        hmc.quantity("250 furlongs")
    with pytest.raises(hmc.InvalidCommand):
        hmc.mm(1).per_s().per_s().per_s()


def test_decode_board_ver_of_both_protocols():
    # Protocol 7 reports both step budgets; a protocol-6 board's VER has 8 values and is no error.
    now = hmc.decode("STX#10#VER#7#100#0#128#50000#322#3#0#40000#192#ETX", board=True)
    assert now.values["max_rate"] == 50000 and now.values["max_ramping_rate"] == 40000
    older = hmc.decode("STX#9#VER#6#100#0#128#50000#322#3#0#127#ETX", board=True)
    assert older.values["protocol"] == 6 and "max_ramping_rate" not in older.values
    with pytest.raises(hmc.FrameError):
        hmc.decode("STX#9#VER#7#100#0#128#50000#322#3#0#128#ETX", board=True)
