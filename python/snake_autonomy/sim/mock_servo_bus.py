"""A mocked Dynamixel bus: N XH540 servos behind a pseudo-terminal, speaking real Protocol 2.0.

The servos are the one simulated servo chain of the C++ core (snake_autonomy._core.dynamixel.
SimulatedServos, include/snake_autonomy/dynamixel/simulated_servos.hpp): the bytes read from the pty
are handed to it raw, its replies are written back. Its rules (control-table memory from
config/dynamixel/<model>.yaml, write checks, hardware errors, every instruction and error status) and
its fault vocabulary are the ones FakeServoBus uses in-process; they are listed and tested there, not
here. ROBOTIS's Python SDK talking to this mock is the independent check (see the tests).
This module keeps what only the pty mock has: the pty and the control socket (PtyServing), and the
ServoBackend that moves the shafts (KinematicServoBackend, or the MuJoCo plant), wired to the servos
as their ShaftHooks (present values refreshed before each read; goals and torque passed on).

Fault injection, switchable at run time, by the Python API (embedded) or by the control socket
(a Unix socket, one JSON object per line, answered by one JSON line; see ``CONTROL_COMMANDS``):
  inject(kind, ids=None, count=None)   kind: drop_reply | corrupt_crc | truncate_reply |
                                       garbage_before | garbage_data (FAULT_KINDS)
  set_silent(id, True)                 a servo that stops answering (it still obeys writes it gets)
  set_hardware_error(id, bits)         bits: int or names, e.g. ["overload", "overheating"]
  close_pty() / reopen_pty()           the pty closing (the symlink goes away) and coming back
  clear_faults(), stats(), reset_stats(), state()

It never dies on what arrives (the C++ servos answer every legal packet or refuse it with the
servo's error status); an exception in the backend costs that one call, counted in
stats()["dropped"] and logged (a last resort: the fuzz tests require 0).
"""
import logging
import threading
import time

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.paths import config_path
from snake_autonomy.sim.pty_serving import CONTROL_COMMANDS, MockBusClient, PtyServing  # noqa: F401 (API)
from snake_autonomy.sim.servo_backend import ServoBackend, ShaftUnits

DEFAULT_TABLE = config_path("dynamixel", "xh540_w270.yaml")
LOG = logging.getLogger(__name__)
FAULT_KINDS = tuple(dx.REPLY_FAULTS)
# Servo error numbers (status packet error byte, bits 0-6), as the C++ servos use them.
RESULT_FAIL = dx.servo_error.RESULT_FAIL
INSTRUCTION_ERROR = dx.servo_error.INSTRUCTION_ERROR
CRC_ERROR = dx.servo_error.CRC_ERROR
DATA_RANGE_ERROR = dx.servo_error.DATA_RANGE_ERROR
DATA_LENGTH_ERROR = dx.servo_error.DATA_LENGTH_ERROR
DATA_LIMIT_ERROR = dx.servo_error.DATA_LIMIT_ERROR
ACCESS_ERROR = dx.servo_error.ACCESS_ERROR


def parse_ids(text: str) -> list:
    """'1-11' or '1,2,5-7' -> sorted IDs; ValueError naming the bad part."""
    ids = set()
    for part in str(text).split(","):
        part = part.strip()
        try:
            if "-" in part:
                lo, hi = (int(x) for x in part.split("-", 1))
                if lo > hi:
                    raise ValueError
                ids.update(range(lo, hi + 1))
            else:
                ids.add(int(part))
        except ValueError:
            raise ValueError(f"--ids: {part!r} in {text!r} is not an ID or a range like 1-11") from None
    bad = [i for i in ids if not 0 <= i <= 252]
    if bad or not ids:
        raise ValueError(f"--ids: {text!r} gives IDs outside 0..252: {bad}" if bad else "--ids: empty")
    return sorted(ids)


class _BackendHooks:
    """The servos' ShaftHooks: the ServoBackend moves the shafts; raw values <-> shaft units by the
    control table (ShaftUnits, shared with the batch simulator's bus)."""

    def __init__(self, servos, backend: ServoBackend, table, clock):
        self._servos, self._backend, self._clock = servos, backend, clock
        self._units = ShaftUnits(table)

    def before_write(self):
        self._backend.advance(self._clock())

    def before_read(self):
        """Present position, velocity, current, voltage, temperature from the backend."""
        backend, put, present = self._backend, self._servos.set_present, self._units.present
        backend.advance(self._clock())
        for i in self._servos.ids:
            put(i, *present(backend.state(i)))

    def on_goal(self, servo_id, ticks):
        self._backend.set_goal(servo_id, self._units.goal_rad(ticks))

    def on_torque(self, servo_id, enabled):
        self._backend.set_torque(servo_id, enabled)


class MockServoBus(PtyServing):
    """The servos' protocol side; the physics is the ServoBackend's; the pty is PtyServing's."""

    def __init__(self, backend: ServoBackend, ids=None, control_table=None, clock=time.monotonic):
        self.table = control_table if isinstance(control_table, dx.ControlTable) else \
            dx.ControlTable.from_yaml(str(control_table or DEFAULT_TABLE))
        ids = list(backend.ids() if ids is None else ids)
        missing = [i for i in ids if i not in backend.ids()]
        if missing:
            raise ValueError(f"ids: {missing} are not moved by the backend (it has {backend.ids()})")
        self.backend = backend
        self._lock = threading.RLock()
        self.servos = dx.SimulatedServos(self.table, ids)
        self._hooks = _BackendHooks(self.servos, backend, self.table, clock)
        self.servos.set_hooks(self._hooks)
        self._hook_errors = 0
        self.reset_stats()
        PtyServing.__init__(self)

    # ------------------------------------------------------------------------------------------
    # fault injection and inspection (thread-safe)
    def inject(self, kind: str, ids=None, count=None):
        """Damage the next `count` replies (None: until cleared) of `ids` (None: every servo)."""
        if kind not in FAULT_KINDS:
            raise ValueError(f"kind: {kind!r} is not one of {FAULT_KINDS}")
        with self._lock:
            self.servos.inject(kind, ids, count)

    def set_silent(self, servo_id: int, silent: bool = True):
        with self._lock:
            self.servos.set_silent(self._check_id(servo_id), bool(silent))

    def set_hardware_error(self, servo_id: int, bits):
        """Hardware Error Status bits (int or names of the YAML's hardware_error_bits); 0 clears."""
        if not isinstance(bits, int):
            names = dict(self.table.hardware_error_bits)
            unknown = [b for b in bits if b not in names]
            if unknown:
                raise ValueError(f"bits: {unknown} not in {sorted(names)}")
            bits = sum(1 << names[b] for b in bits)
        if not 0 <= bits <= 255:
            raise ValueError(f"bits: {bits} is not in 0..255")
        with self._lock:
            self.servos.set_hardware_error(self._check_id(servo_id), bits)  # torque off: on_torque tells the backend

    def clear_faults(self):
        with self._lock:
            self.servos.clear_faults()

    def reset_stats(self):
        with self._lock:
            self.servos.reset_stats()
            self._hook_errors = self.servos.hook_errors
            self._late_drops = 0

    def stats(self) -> dict:
        """Counts of what the mock received and sent since start or reset_stats()."""
        with self._lock:
            out = self.servos.stats()
            out["dropped"] += self.servos.hook_errors - self._hook_errors
            out["late_dropped"] = self._late_drops
            ids = self.servos.ids
            out["goal_writes"] = {str(i): self.servos.goal_writes(i) for i in ids}
            out["goal_writes_total"] = sum(out["goal_writes"].values())
            out["goal_ticks"] = {str(i): self.servos.get(i, "goal_position") for i in ids}
            return out

    def state(self) -> dict:
        """Per servo: goal and present ticks, torque, hardware error bits, Return Delay Time."""
        with self._lock:
            self._hooks.before_read()
            get = self.servos.get
            return {str(i): {"goal_ticks": get(i, "goal_position"),
                             "present_ticks": get(i, "present_position"),
                             "torque": bool(get(i, "torque_enable")),
                             "hardware_error": get(i, "hardware_error_status"),
                             "return_delay_us": 2 * get(i, "return_delay_time"),
                             "silent": self.servos.silent(i)}
                    for i in self.servos.ids}

    def _check_id(self, servo_id) -> int:
        if not isinstance(servo_id, int) or not 0 <= servo_id <= 252 or not self.servos.has(servo_id):
            raise ValueError(f"id: {servo_id!r} is not on this bus ({self.servos.ids})")
        return servo_id

    # ------------------------------------------------------------------------------------------
    # protocol: bytes in, bytes out (usable without a pty)
    def _clear_input(self):
        self.servos.clear_input()

    def _late_dropped(self):  # (called with _lock held by PtyServing)
        self._late_drops += 1

    def handle(self, data: bytes, latest_only: bool = False) -> bytes:
        """Feed received bytes; returns the bytes the servos send back. latest_only (the pty): when
        several packets came in one read, only the last one is answered (the master gave up on the
        earlier ones; their writes still act), counted as superseded."""
        with self._lock:
            errors = self.servos.hook_errors
            out = self.servos.handle(bytes(data), latest_only)
            if self.servos.hook_errors != errors:
                LOG.error("mock servo bus: the servo backend raised %d time(s) answering %d bytes: %s",
                          self.servos.hook_errors - errors, len(data), self.servos.last_hook_error)
            return out
