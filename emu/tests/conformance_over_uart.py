#!/usr/bin/python3
"""Plays every conformance vector a board answers (the `line` and `stream` vectors, in both
checksum modes) over a board's serial line, one vector at a time, waiting for its replies,
against two boards — the emulated image (hmc-emu) and the host-built firmware core (hmc-sim) —
and fails on any reply that differs, except the differences listed with their reasons in
uart_differences.json beside this script (nothing else may differ).

After every vector all three motors are stopped (those replies are compared too), so each
vector starts from motors at rest: a vector that starts a motor does not leave it running into
a limit switch or eating the step-rate budget of the next one. A CRC-16 vector is played between
CRC#1 (sent in the seed's sum mode) and CRC#0 (sent in CRC-16 mode), its stops in CRC-16 mode.
The `board_line` vectors are frames a board sends, not ones it receives: they are checked by
conformance_test against the firmware's reply writer, not here.

Usage: conformance_over_uart.py VECTORS_DIR -- HMC_EMU_COMMAND... -- HMC_SIM_COMMAND...
Without the image named in HMC_EMU_COMMAND the test is skipped (exit 77), unless CI=true.
"""
import json
import os
import pathlib
import selectors
import subprocess
import sys
import time

TIMEOUT_S = 20.0


def vectors(directory, mode="sum"):
    """(id, bytes to send, replies expected) of the vectors in checksum mode `mode`."""
    for path in sorted(pathlib.Path(directory).glob("*.json")):
        if path.name.startswith("behaviour_"):
            continue
        for vector in json.loads(path.read_text(encoding="utf-8"))["vectors"]:
            if vector.get("checksum_mode", "sum") != mode:
                continue
            data = vector["input"].encode("latin-1")
            if vector["kind"] == "line":
                replies = 0 if vector["expect"].get("verdict") == "ignored" else 1
                yield vector["id"], data + b"\n", replies
            elif vector["kind"] == "stream":
                if not data.endswith((b"\n", b"\r")):
                    data += b"\n"
                yield vector["id"], data, len(vector["expect"])


def crc16(data):
    """docs/protocol.md, CRC-16 mode: polynomial 0x1021, initial 0xFFFF, no reflection."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1) & 0xFFFF
    return crc


def frame(name, values, mode):
    head = b"STX#%d#%s#" % (len(values) + 1, name) + b"".join(b"%d#" % v for v in values)
    check = b"%05d" % crc16(head) if mode == "crc16" else b"%d" % (sum(values) % 256)
    return head + check + b"#ETX\n"


def stop_all(mode):
    return b"".join(frame(b"STM", (m, 0, 0, 0, 0), mode) for m in (1, 2, 3))


class Board:
    def __init__(self, command):
        self.name = pathlib.Path(command[0]).name
        self.process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.process.stdout, selectors.EVENT_READ)
        self.buffer = b""
        self.events = []

    def line(self, deadline):
        while b"\n" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not self.selector.select(left):
                raise TimeoutError(f"no reply from {self.name} within {TIMEOUT_S} s")
            chunk = os.read(self.process.stdout.fileno(), 65536)
            if not chunk:
                raise EOFError(f"{self.name}'s output ended")
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line.decode("latin-1")

    def exchange(self, data, count, timeout=TIMEOUT_S):
        """Sends `data`; returns the next `count` replies (events are set aside)."""
        self.process.stdin.write(data)
        self.process.stdin.flush()
        deadline = time.monotonic() + timeout
        replies = []
        while len(replies) < count:
            line = self.line(deadline)
            if line.startswith("STX#") and line.split("#")[2].startswith("E"):
                self.events.append(line)
            else:
                replies.append(line)
        return replies

    def close(self):
        self.process.stdin.close()
        try:
            self.process.wait(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
        return self.process.returncode


def settle(board):
    """Ends the power-up self-test (the image always runs it): the three stops are sent and
    every line up to the answer of a VER sent after them is set aside."""
    board.process.stdin.write(stop_all("sum") + b"STX#1#VER#0#ETX\n")
    board.process.stdin.flush()
    deadline = time.monotonic() + TIMEOUT_S
    while "#VER#" not in board.line(deadline):
        pass


def differences(path, scope="conformance"):
    """The listed differences that apply to `scope` (conformance or behaviour)."""
    listed = json.loads(pathlib.Path(path).read_text(encoding="utf-8"))["differences"]
    return [d for d in listed if d.get("scope", scope) == scope]


def comparable(reply, masked):
    """`reply` with the fields of every listed difference that applies to it replaced by '*'."""
    fields = reply.split("#")
    for d in masked:
        when = d.get("when")
        if len(fields) > 3 and fields[2] == d["reply"] and (
                when is None or (len(fields) > when["field"] and fields[when["field"]] in when["in"])):
            fields = ["*" if i in d["masked_fields"] else f for i, f in enumerate(fields)]
    return "#".join(fields)


def plays():
    """(id, [(bytes, replies), ...]) for every vector, with its stops and mode switches."""
    for vector_id, data, count in vectors(DIRECTORY):
        yield vector_id, data, [(data, count), (stop_all("sum"), 3)]
    for vector_id, data, count in vectors(DIRECTORY, "crc16"):
        yield vector_id, data, [(frame(b"CRC", (1,), "sum"), 1), (data, count),
                                (stop_all("crc16"), 3), (frame(b"CRC", (0,), "crc16"), 1)]


def main(argv):
    global DIRECTORY
    DIRECTORY = argv[1]
    split = argv.index("--", 2)
    rest = argv[split + 1:]
    split2 = rest.index("--")
    emu_command, sim_command = rest[:split2], rest[split2 + 1:]
    image = next((a for a in emu_command[1:] if a.endswith(".elf")), None)
    if image is not None and not os.path.isfile(image):
        if os.environ.get("CI") == "true":
            print(f"FAIL: no firmware image {image} (build the firmware preset first)")
            return 1
        print(f"SKIP: no firmware image {image}")
        return 77
    masked = differences(pathlib.Path(__file__).with_name("uart_differences.json"))
    emu, sim = Board(emu_command), Board(sim_command)
    for board in (emu, sim):
        settle(board)
    failures = played = 0
    for vector_id, data, exchanges in plays():
        played += 1
        try:
            got = [r for d, n in exchanges for r in emu.exchange(d, n)]
            want = [r for d, n in exchanges for r in sim.exchange(d, n)]
        except (TimeoutError, EOFError) as error:
            print(f"FAIL {vector_id}: input {data!r}: {error}")
            failures += 1
            break
        if [comparable(r, masked) for r in got] != [comparable(r, masked) for r in want]:
            failures += 1
            print(f"FAIL {vector_id}: input {data!r}\n  hmc-sim: {want}\n  hmc-emu: {got}")
    emu_code, sim_code = emu.close(), sim.close()
    if emu_code != 0:
        failures += 1
        print(f"FAIL hmc-emu exited with {emu_code}")
    print(f"conformance over the emulated UART: {played} vectors, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
