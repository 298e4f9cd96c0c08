#!/usr/bin/python3
"""Bursts of command lines sent back to back at 115200 baud (the image's only rate, the highest
it supports) to the real image on hmc-emu, while the motors step: no received byte may be lost
(every line answered as it would be alone, the USART's overflow count 0), and a flood the board
cannot answer as fast as it arrives ends in clean refusals, never in a spliced line taken for
another or a hang.

  1. During the power-up self-test (three motors ramping): 200 LED lines, each answered ACK.
  2. Motor 3 running at 20 us a step, the spec's fastest (50 000 steps/s): 300 stops of the idle
     motors 1 and 2, each answered ACK.
  3. All three motors at the spec's 20 us a step (150 000 steps/s: the whole budget): 100 LED
     lines, each answered ACK.
  In each, every STEP pulse is at least 2.0 us high and 1.9 us low (the DRV8711's minimum).
  4. 100 VER lines at once: a VER reply (51 bytes) is longer than the line (16 bytes), so the
     board falls behind and its receive ring fills. Every answer must be the VER reply or
     NAK bad_byte (the line that lost bytes, marked where they were lost), never another
     refusal of a line spliced from two; after a blank line (which closes a line whose end was
     lost) VER is answered again.

Usage: uart_burst_test.py HMC_EMU IMAGE
"""
import os
import re
import selectors
import subprocess
import sys
import time

import image_check

ACK = "STX#1#ACK#0#ETX"
VER_REPLY = re.compile(r"STX#10#VER#\d+#\d+#0#128#\d+#\d+#\d+#\d+#\d+#\d+#ETX")
BAD_BYTE = re.compile(r"STX#4#NAK#2#\d+#\d+#\d+#ETX")
LED_OFF = b"STX#6#LED#1#0#0#0#0#1#ETX\n"
VER = b"STX#1#VER#0#ETX\n"


def stm(motor, direction, microstep, steps, delay_us):
    values = (motor, direction, microstep, steps, delay_us)
    fields = b"#".join(b"%d" % v for v in values)
    return b"STX#6#STM#%s#%d#ETX\n" % (fields, sum(values) % 256)


STOP_IDLE = stm(1, 0, 0, 0, 0) + stm(2, 0, 0, 0, 0)
STOP_ALL = stm(1, 0, 0, 0, 0) + stm(2, 0, 0, 0, 0) + stm(3, 0, 0, 0, 0)


class Emu:
    def __init__(self, emu, image):
        self.process = subprocess.Popen(
            [emu, image, "--fast", "--quiet", "--stats", "--max-time", "60"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.process.stdout, selectors.EVENT_READ)
        self.buffer = b""

    def send(self, data):
        self.process.stdin.write(data)
        self.process.stdin.flush()

    def replies(self, count, timeout=30.0):
        """The next `count` lines that are not events (EV...), or fewer at the timeout."""
        deadline = time.monotonic() + timeout
        got = []
        while len(got) < count:
            while b"\n" not in self.buffer:
                left = deadline - time.monotonic()
                if left <= 0 or not self.selector.select(left):
                    return got
                chunk = os.read(self.process.stdout.fileno(), 65536)
                if not chunk:
                    return got
                self.buffer += chunk
            line, self.buffer = self.buffer.split(b"\n", 1)
            text = line.decode("latin-1")
            if not text.split("#")[2:3] or not text.split("#")[2].startswith("EV"):
                got.append(text)
        return got

    def replies_until_quiet(self, quiet=1.5):
        """Every reply until none has come for `quiet` seconds."""
        got = []
        while True:
            more = self.replies(1, timeout=quiet)
            if not more:
                return got
            got += more

    def finish(self):
        _, err = self.process.communicate(timeout=60)  # closes standard input: the run ends
        return self.process.returncode, err.decode()


def lost_bytes(stats):
    found = re.search(r"command UART: (\d+) received bytes lost to overflow", stats)
    return int(found.group(1)) if found else None


def step_interrupts(stats):
    """The three step interrupts' entries (one per motor's compare: TCC1, TCC2, TC4)."""
    return sum(int(n) for exception, n in re.findall(r"exception (\d+): (\d+) entries", stats)
               if int(exception) in (32, 33, 35))


def main(emu_path, image):
    failures = []

    def check(name, ok, detail=""):
        print(("ok   " if ok else "FAIL ") + name + ("" if ok else ": " + detail))
        if not ok:
            failures.append(name)

    def expect_acks(name, emu, count):
        got = emu.replies(count)
        check(f"{name}: {count} ACKs", got == [ACK] * count,
              f"{len(got)} replies, not ACK: {sorted(set(got) - {ACK})}")

    def expect_clean_end(name, emu, min_steps):
        code, stats = emu.finish()
        check(f"{name}: hmc-emu exit 0", code == 0, f"exit {code}: {stats}")
        check(f"{name}: no byte lost to the USART's overflow", lost_bytes(stats) == 0, stats)
        check(f"{name}: motors stepped meanwhile ({min_steps}+ step interrupts)",
              step_interrupts(stats) >= min_steps, stats)
        pulses = re.findall(r"STEP (\d): \d+ pulses, high ([\d.]+)-[\d.]+ ns, low >= ([\d.-]+) ns", stats)
        check(f"{name}: every STEP pulse >= 2.0 us high, >= 1.9 us low",
              pulses and all(float(high) >= 1999 and float(low) >= 1900 for _, high, low in pulses),
              stats)

    # 1. The self-test ramps all three motors from the boot on; the lines arrive right after the
    # boot event and end before the self-test does (200 x 26 bytes = 0.45 s).
    emu = Emu(emu_path, image)
    emu.send(LED_OFF * 200)
    expect_acks("self-test", emu, 200)
    emu.send(STOP_ALL)
    emu.replies(3)
    expect_clean_end("self-test", emu, 2000)

    # 2. One motor at the spec's fastest rate.
    emu = Emu(emu_path, image)
    emu.send(STOP_ALL)
    emu.replies(3)
    emu.send(stm(3, 1, 8, 0, 20) + STOP_IDLE * 150)
    expect_acks("motor 3 at 20 us", emu, 301)
    emu.send(STOP_ALL)
    emu.replies(3)
    expect_clean_end("motor 3 at 20 us", emu, 8000)

    # 3. Three motors sharing the budget (5000 steps each at microstep 8 stay clear of the
    # switches of motors 1 and 2: 160 000 of the 204 800 units to the far one).
    emu = Emu(emu_path, image)
    emu.send(STOP_ALL)
    emu.replies(3)
    emu.send(b"".join(stm(m, 1, 8, 5000, 20) for m in (1, 2, 3)) + LED_OFF * 100)
    expect_acks("three motors at 20 us", emu, 103)
    emu.send(STOP_ALL)
    emu.replies(3)
    expect_clean_end("three motors at 20 us", emu, 4000)

    # 4. A flood the board cannot answer at the rate it arrives.
    emu = Emu(emu_path, image)
    emu.send(STOP_ALL)
    emu.replies(3)
    emu.send(VER * 100)
    got = emu.replies_until_quiet()
    unclean = [r for r in got if not VER_REPLY.fullmatch(r) and not BAD_BYTE.fullmatch(r)]
    check("VER flood: every answer a VER reply or NAK bad_byte", not unclean and got,
          f"{len(got)} answers, {len(unclean)} others: {sorted(set(unclean))}")
    # A flood that ended in a loss left its last line open (its end was lost): a blank line
    # closes it (one more NAK bad_byte), and the next line is answered.
    emu.send(b"\n" + VER)
    again = emu.replies(1)
    if again and BAD_BYTE.fullmatch(again[0]):
        again = emu.replies(1)
    check("VER flood: answered again afterwards", len(again) == 1 and VER_REPLY.fullmatch(again[0]), str(again))
    code, stats = emu.finish()
    check("VER flood: hmc-emu exit 0", code == 0, f"exit {code}: {stats}")
    check("VER flood: no byte lost to the USART's overflow", lost_bytes(stats) == 0, stats)

    print(f"uart_burst_test: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    image_check.require_image(sys.argv[2])
    sys.exit(main(sys.argv[1], sys.argv[2]))
