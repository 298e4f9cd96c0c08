# Shared by the hmc module's tests: a private directory for sim://'s saved boards, unique board
# names, and hmc-sim over TCP (HMC_SIM: the binary, set by CTest) with its control channel.
import itertools
import os
import re
import socket
import subprocess
import sys
import tempfile

import pytest

STATE = tempfile.mkdtemp(prefix="hmc-python-test-")
os.environ["HMC_SIM_STATE"] = STATE  # before any board is opened
os.environ.pop("HMC_PORT", None)

import hmc  # noqa: E402  (after HMC_SIM_STATE)

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.environ.get("HMC_EXAMPLES", os.path.join(HERE, "..", "..", "examples"))
_names = itertools.count(1)


@pytest.fixture
def sim_url():
    """A fresh simulated board of its own, in fast virtual time: sim_url() or sim_url('legacy')."""

    def make(*options):
        name = f"t{os.getpid()}-{next(_names)}"
        return "sim://" + name + "?" + "&".join(("fast", "fresh") + options)

    return make


@pytest.fixture
def examples():
    return EXAMPLES


class SimServer:
    """hmc-sim serving the protocol over TCP, with its control channel for switches."""

    def __init__(self, *options):
        binary = os.environ.get("HMC_SIM")
        if not binary or not os.access(binary, os.X_OK):
            pytest.skip("HMC_SIM (the hmc-sim binary) is not set: run through ctest")
        self.process = subprocess.Popen(
            [binary, "--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0", "--no-self-test", *options],
            stderr=subprocess.PIPE, text=True)
        self.port = self.control_port = None
        while self.port is None or self.control_port is None:
            line = self.process.stderr.readline()
            if not line:
                raise RuntimeError("hmc-sim did not start")
            found = re.search(r"(control )?listening on tcp://127\.0\.0\.1:(\d+)", line)
            if found and found.group(1):
                self.control_port = int(found.group(2))
            elif found:
                self.port = int(found.group(2))
        self.url = f"tcp://127.0.0.1:{self.port}"

    def control(self, command):
        with socket.create_connection(("127.0.0.1", self.control_port), timeout=5) as s:
            s.sendall(command.encode() + b"\n")
            answer = b""
            while not answer.endswith(b"\n"):
                chunk = s.recv(65536)
                if not chunk:
                    break
                answer += chunk
        return answer.decode().strip()

    def stop(self):
        if self.process.poll() is None:
            self.process.terminate()
            self.process.wait(timeout=10)
        self.process.stderr.close()


@pytest.fixture
def sim_server():
    servers = []

    def start(*options):
        server = SimServer(*options)
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.stop()


def run_python(code, *args, **kwargs):
    """Runs `code` in a child interpreter (this one) with the module on its path."""
    return subprocess.Popen([sys.executable, "-c", code, *args], env=dict(os.environ), **kwargs)
