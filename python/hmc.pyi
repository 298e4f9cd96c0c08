"""Type stubs of the hmc module (python/module.cpp): the Hybrid Motor Controller from Python."""

import os
from typing import Callable, Iterator, Optional, Sequence, Tuple, Union

Number = Union[int, float]
QuantityLike = Union["Quantity", str, int, float]
AxisLike = Union[int, str]
PathLike = Union[str, "os.PathLike[str]"]
Colour = Union[str, Tuple[int, int, int], Tuple[int, int, int, int], Sequence[int]]

__version__: str

class Error(Exception): ...

class Refused(Error):
    reason: Optional[str]
    code: Optional[int]
    by_board: bool
    token: Optional[int]
    offset: Optional[int]

class InvalidCommand(Refused, ValueError): ...
class FirmwareTooOld(Refused): ...
class NoReply(Error, TimeoutError): ...
class LinkLost(Error, ConnectionError): ...
class PortError(Error, OSError): ...

class MotionEndedEarly(Error):
    motor: int
    how: str
    position: int
    status: Motor

class FrameError(Error, ValueError):
    reason: Optional[str]
    code: int
    token: Optional[int]
    offset: int
    field: str
    expected: int
    found: int
    input: str

class MotionFileError(Error, ValueError):
    errors: list[Mistake]

class ProfileError(Error, ValueError):
    path: str
    mistakes: list[Tuple[int, int, str]]

class RoundingWarning(UserWarning): ...

class Quantity:
    @property
    def value(self) -> float: ...
    @property
    def unit(self) -> str: ...
    @property
    def dimension(self) -> str: ...
    def per_s(self) -> Quantity: ...
    def __neg__(self) -> Quantity: ...

def mm(value: Number) -> Quantity: ...
def deg(value: Number) -> Quantity: ...
def rev(value: Number) -> Quantity: ...
def steps(value: Number) -> Quantity: ...
def quantity(text: str) -> Quantity: ...

class Motor:
    motor: int
    state: str
    position: int
    target: int
    board_position: int
    microstep: int
    rate: int
    homed: bool
    endless: bool
    switch_reverse: bool
    switch_forward: bool
    last_end: Optional[str]
    axis: Optional[str]
    unit: Optional[str]
    units: Optional[float]
    target_units: Optional[float]
    rate_units: Optional[float]

class Servo:
    servo: int
    pulse_us: int

class Strip:
    strip: int
    r: int
    g: int
    b: int
    w: int
    colour: str

class Status:
    board: str
    firmware: str
    reported: bool
    emergency: bool
    motors: list[Motor]
    servos: list[Servo]
    strips: list[Strip]
    watchdog_ms: Optional[int]
    watchdog_fired: bool
    last_reset: Optional[str]

class Event:
    kind: str
    motor: Optional[int]
    how: Optional[str]
    position: Optional[int]
    board_position: Optional[int]
    pressed: Optional[bool]
    end: Optional[int]
    homed: Optional[bool]
    text: str
    line: str
    time: float

class Frame:
    name: str
    event: bool
    values: dict[str, int]
    description: str
    frame: str
    canonical: bool
    warnings: list[str]

class Progress:
    kind: str
    step: int
    total: int
    description: str
    elapsed_s: float
    remaining_s: float

class Mistake:
    file: str
    line: int
    column: int
    path: str
    expected: str
    found: str
    message: str

class Action:
    index: int
    kind: str
    description: str
    start_s: float
    end_s: float
    line: int
    column: int
    estimated: bool

class Track:
    name: str
    motor: int
    microstep: int
    start_position: int
    end_position: int
    t: list[float]
    velocity: list[float]
    stage_boundaries_s: list[float]

class Plan:
    @property
    def duration_s(self) -> float: ...
    @property
    def actions(self) -> list[Action]: ...
    @property
    def tracks(self) -> list[Track]: ...
    def svg(self, title: Optional[str] = None) -> str: ...
    def csv(self) -> str: ...

def encode(*command: Union[str, int], crc: bool = False) -> str: ...
def decode(line: str, *, board: bool = False, crc: bool = False) -> Frame: ...
def check(path: PathLike, *, profile: Optional[PathLike] = None) -> Plan: ...
def plan(path: PathLike, *, profile: Optional[PathLike] = None, firmware: str = "v2", baud: int = 115200) -> Plan: ...

class EventIterator(Iterator[Event]):
    def __iter__(self) -> EventIterator: ...
    def __next__(self) -> Event: ...

class Board:
    @property
    def description(self) -> str: ...
    @property
    def firmware(self) -> str: ...
    @property
    def protocol(self) -> Optional[int]: ...
    @property
    def simulated(self) -> bool: ...
    @property
    def watchdog_armed(self) -> bool: ...
    @property
    def axes(self) -> list[str]: ...
    @property
    def closed(self) -> bool: ...
    def move(
        self,
        axis: AxisLike,
        *,
        to: Optional[QuantityLike] = None,
        by: Optional[QuantityLike] = None,
        steps: Optional[int] = None,
        speed: Optional[QuantityLike] = None,
        accel: Optional[QuantityLike] = None,
        wait: bool = True,
        keep_running: bool = False,
        timeout: Optional[float] = None,
    ) -> Motor: ...
    def run(self, axis: AxisLike, rate: QuantityLike, *, accel: Optional[QuantityLike] = None, keep_running: bool = False) -> None: ...
    def stop(self, axis: Union[None, AxisLike, Sequence[AxisLike]] = None) -> None: ...
    def home(self, axis: Union[None, AxisLike, Sequence[AxisLike]] = None) -> None: ...
    def step_budgets(self) -> Tuple[int, int]: ...
    def zero(self, axis: AxisLike, position: QuantityLike = 0) -> Motor: ...
    def wait(self, axis: Union[None, AxisLike, Sequence[AxisLike]] = None, timeout: Optional[float] = None) -> None: ...
    def servo(self, servo: int, angle: float) -> None: ...
    def led(self, strip: int, colour: Colour) -> None: ...
    def status(self) -> Status: ...
    def send(self, command: str, *, raw: bool = False) -> Frame: ...
    def arm_watchdog(self, timeout: float) -> None: ...
    def disarm_watchdog(self) -> None: ...
    def on_event(self, callback: Callable[[Event], object]) -> None: ...
    def events(self, timeout: Optional[float] = None) -> EventIterator: ...
    def listen(self, seconds: float) -> None: ...
    def run_file(
        self,
        path: PathLike,
        *,
        progress: Optional[Callable[[Progress], object]] = None,
        start_at: int = 1,
        at: Optional[Tuple[Optional[float], Optional[float], Optional[float]]] = None,
    ) -> int: ...
    def close(self) -> None: ...
    def __enter__(self) -> Board: ...
    def __exit__(self, *exc: object) -> bool: ...

def open(
    port: Optional[str] = None,
    profile: Optional[PathLike] = None,
    *,
    baud: Optional[int] = None,
    timeout: float = 1.0,
    firmware: str = "auto",
    watchdog: float = 0.5,
) -> Board: ...
