#!/usr/bin/python3
"""The devices on the emulated board's pins against hmc-sim's trace, for the same frames.

One script (hmc-sim's script language) is played to the real image on hmc-emu and to the
host-built core on hmc-sim, both with --trace. hmc-sim traces what the core asks its hardware
for; hmc-emu traces what its devices decode from the pins: the servo pulse measured on each servo
pin from TCC0's waveform output, each strip's colours decoded from the SK6812 bitstream its
SERCOM sends on the strip's pin, the buzzer's frequency from TC3's output, switches, the STEP
edges. They must agree:

  - servos: per servo, the sequence of pulse widths and releases (a repeat collapsed) is equal,
    every pulse is an angle the script asked for (544 + angle*1856/180 us, rounded), and no
    other width ever reaches the pin (a short first pulse would be one). One SVM to a released
    servo is timed to arrive 0.25 ms into a TCC0 period, inside the pulse the channel still
    generates (servo 1's last, 647 us): a pin handed to TCC0 there at once would carry a short
    first pulse (issue 17); the image's hand-over (servo_pwm.h) waits for the pulse to end. The
    period's phase is read from a first short run (the first boot pulse's rising edge);
  - LED strips: per strip, the sequence of colours is equal, hmc-sim's scaled by the board's
    brightness (firmware/targets/samd21/board.h, kLedBrightness: the image scales before it
    encodes, the core's trace is before the scaling); every frame is whole: 90 LEDs, one colour;
  - tones: the same frequencies in the same order, lengths within 2 ms (hmc-emu measures the
    tone on the pin; the main loop ends it);
  - switches and the emergency switch: the same changes in the same order;
  - STEP edges: the same count and final position per motor (the power-up self-test);
  - booting LEDs: the same sequence of states;
  - a trace file that cannot be written: exit 3, naming it.

Usage: devices_trace_test.py HMC_EMU IMAGE HMC_SIM BOARD_H
"""
import json
import os
import re
import subprocess
import sys
import tempfile

import image_check

SERVO_ANGLES = {1: [135, 10, 170], 2: [30]}
TICKS_PER_US = 48
PERIOD_TICKS = 20000 * TICKS_PER_US  # servo_pwm.h: 20 ms
BYTE_TICKS = 10 * 1000000 * TICKS_PER_US // 115200  # 8N1 at 115200 baud


def frame(name, *values):
    fields = "#".join(str(v) for v in values)
    return f"STX#{len(values) + 1}#{name}#{fields}#{sum(values) % 256}#ETX"


SCRIPT = f"""
at 1s send {frame("SVM", 1, 135)}
at 1100ms send {frame("SVM", 2, 30)}
at 1200ms send {frame("LED", 1, 255, 64, 0, 10)}
at 1300ms send {frame("LED", 2, 1, 2, 3, 250)}
at 1400ms send {frame("SVM", 1, 10)}
at 1600ms send {frame("LED", 1, 0, 0, 0, 0)}
at 1602ms send {frame("LED", 1, 17, 34, 51, 68)}
at 1800ms send {frame("SVM", 3, 90)}
at 2100ms press 1 1
at 2150ms release 1 1
at 2200ms estop
at 2250ms estop release
at 2600ms send STX#1#VER#0#ETX
"""


def handover_line(first_rise):
    """A script line whose SVM reaches the board 0.25 ms into the first TCC0 period after 2 s.

    `first_rise`: the tick of the first servo pulse's rising edge (a period start)."""
    line = frame("SVM", 1, 170)
    period = first_rise + ((2000000 * TICKS_PER_US - first_rise) // PERIOD_TICKS + 1) * PERIOD_TICKS
    at = period + 250 * TICKS_PER_US - (len(line) + 1) * BYTE_TICKS
    return f"at {at}t send {line}\n"


def pulse_us(angle):
    return 544 + (angle * 1856 + 90) // 180


def angle_of(pulse):
    """The angle whose pulse this is (the inverse of pulse_us over 10..170 degrees)."""
    for angle in range(0, 181):
        if pulse_us(angle) == pulse:
            return angle
    return None


def events(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def collapse(sequence):
    out = []
    for item in sequence:
        if not out or out[-1] != item:
            out.append(item)
    return out


def servo_sequence(trace, servo):
    return collapse(["released" if e.get("released") else e["pulse_us"]
                     for e in trace if e["ev"] == "servo" and e["servo"] == servo])


def main(emu, image, sim, board_h):
    brightness = int(re.search(r"kLedBrightness = (\d+)", open(board_h).read()).group(1))
    scale = lambda v: (v * (brightness + 1)) >> 8  # firmware/targets/samd21/sk6812.h, scale()
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    with tempfile.TemporaryDirectory() as work:
        bad = subprocess.run([emu, image, "--fast", "--max-time", "0.01", "--trace", os.path.join(work, "no", "t")],
                             stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
        check(bad.returncode == 3 and "cannot write trace" in bad.stderr,
              f"a trace file that cannot be written: exit 3 naming it (exit {bad.returncode}: {bad.stderr.strip()})")
        emu_trace = os.path.join(work, "emu.jsonl")
        subprocess.run([emu, image, "--fast", "--quiet", "--max-time", "0.1", "--trace", emu_trace],
                       stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
        first = next(e for e in events(emu_trace) if e["ev"] == "servo")
        first_rise = first["t"] - first["pulse_us"] * TICKS_PER_US
        script = os.path.join(work, "script.txt")
        with open(script, "w") as f:
            f.write(SCRIPT)
            f.write(handover_line(first_rise))
        sim_trace = os.path.join(work, "sim.jsonl")
        emu_run = subprocess.run([emu, image, "--fast", "--quiet", "--max-time", "2.8", "--script", script,
                                  "--trace", emu_trace], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, timeout=300)
        check(emu_run.returncode == 6, f"hmc-emu ran to --max-time (exit {emu_run.returncode}: {emu_run.stderr.strip()})")
        sim_run = subprocess.run([sim, "--fast", "--quiet", "--exit-when-idle", "--script", script,
                                  "--trace", sim_trace], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, timeout=120)
        check(sim_run.returncode == 0, f"hmc-sim ran the script (exit {sim_run.returncode}: {sim_run.stderr.strip()})")
        check(emu_run.stdout.split() == sim_run.stdout.split(),
              "the image's answers equal hmc-sim's:\n  " + " ".join(emu_run.stdout.split()) + "\n  " +
              " ".join(sim_run.stdout.split()))
        emu_ev = events(emu_trace)
        sim_ev = events(sim_trace)

    for servo in (1, 2):
        got, want = servo_sequence(emu_ev, servo), servo_sequence(sim_ev, servo)
        check(got == want, f"servo {servo}: pulses on the pin {got} == hmc-sim's {want}")
        angles = [angle_of(p) for p in got if p != "released"]
        check(angles == [90] + SERVO_ANGLES[servo],
              f"servo {servo}: the angles decoded from the pin {angles} are centred, then the script's {SERVO_ANGLES[servo]}")

    for strip in (1, 2):
        emu_leds = [e for e in emu_ev if e["ev"] == "led" and e["strip"] == strip]
        whole = all(set(e) == {"t", "ev", "strip", "r", "g", "b", "w"} for e in emu_leds)
        check(whole and emu_leds, f"strip {strip}: every frame decoded from the bitstream is whole (90 LEDs, one colour)")
        got = collapse([(e["r"], e["g"], e["b"], e["w"]) for e in emu_leds])
        want = collapse([(scale(e["r"]), scale(e["g"]), scale(e["b"]), scale(e["w"]))
                         for e in sim_ev if e["ev"] == "led" and e["strip"] == strip])
        check(got == want, f"strip {strip}: colours decoded {got} == hmc-sim's at brightness {brightness} {want}")

    emu_tones = [(e["hz"], e["ms"]) for e in emu_ev if e["ev"] == "tone"]
    sim_tones = [(e["hz"], e["ms"]) for e in sim_ev if e["ev"] == "tone" and e["hz"] != 0]
    check([hz for hz, _ in emu_tones] == [hz for hz, _ in sim_tones] and
          all(abs(a[1] - b[1]) <= 2 for a, b in zip(emu_tones, sim_tones)),
          f"tones on the buzzer's pin {emu_tones} == hmc-sim's {sim_tones} (ms within 2)")

    def switch_changes(trace):
        return [(e["ev"], e.get("motor"), e.get("end"), e["pressed"]) for e in trace if e["ev"] in ("switch", "emergency")]
    check(switch_changes(emu_ev) == switch_changes(sim_ev) and switch_changes(emu_ev),
          f"switch changes {switch_changes(emu_ev)} == hmc-sim's")

    for motor in (1, 2, 3):
        emu_steps = [e["pos"] for e in emu_ev if e["ev"] == "step" and e["motor"] == motor]
        sim_steps = [e["pos"] for e in sim_ev if e["ev"] == "step" and e["motor"] == motor]
        check(len(emu_steps) == len(sim_steps) > 0 and emu_steps[-1] == sim_steps[-1],
              f"motor {motor}: {len(emu_steps)} STEP edges ending at {emu_steps[-1:]} == hmc-sim's {len(sim_steps)} at {sim_steps[-1:]}")

    boot = lambda trace: collapse([(e["left"], e["right"]) for e in trace if e["ev"] == "boot_leds"])
    check(boot(emu_ev) == boot(sim_ev) and len(boot(emu_ev)) >= 3,
          f"booting LEDs {boot(emu_ev)} == hmc-sim's {boot(sim_ev)}")

    if failures:
        print(f"{len(failures)} failed")
        return 1
    print("all passed")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    image_check.require_image(sys.argv[2])
    sys.exit(main(*sys.argv[1:]))
