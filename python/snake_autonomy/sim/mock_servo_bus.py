"""A mocked Dynamixel bus: N XH540 servos behind a pseudo-terminal, speaking real Protocol 2.0.

The packets go through the project's C++ codec (snake_autonomy._core.dynamixel), the very code the
driver uses; ROBOTIS's Python SDK talking to this mock is the independent check (see the tests).
Each servo has its control-table memory (defaults from config/dynamixel/<model>.yaml) and behaves
like the real one where the driver cares: writes outside [min, max] or the position limits are
refused (data limit error), EEPROM entries are refused while torque is on (access error), a
hardware error sets the alert bit in every status packet and turns torque off, REBOOT clears it.
The shafts move through a ServoBackend (KinematicServoBackend, or the MuJoCo plant).

Fault injection, switchable at run time, by the Python API (embedded) or by the control socket
(a Unix socket, one JSON object per line, answered by one JSON line; see ``CONTROL_COMMANDS``):
  inject(kind, ids=None, count=None)   kind: corrupt_crc | drop_reply | truncate_reply | garbage_before
  set_silent(id, True)                 a servo that stops answering (it still obeys writes it gets)
  set_hardware_error(id, bits)         bits: int or names, e.g. ["overload", "overheating"]
  close_pty() / reopen_pty()           the pty closing (the symlink goes away) and coming back
  clear_faults(), stats(), reset_stats(), state()

It never dies on what arrives: a legal packet gets its answer or the servo's error status (data
length error for a wrong parameter count or a reply too long for one packet, data range error for
a read beyond the control table, instruction error for an unknown instruction), a packet with a
bad CRC addressed to one of its servos gets a CRC error status (silence when broadcast or not
ours, or when its header is damaged), and any exception the dispatch did not foresee drops that one
packet, counted in stats()["dropped"] and logged (a last resort: the fuzz tests require 0).

Fast sync read replies: one status packet from ID 0xFE whose parameters are, per servo,
ERR ID DATA CRC(2) (the last block's CRC is the packet's). The intermediate CRCs are the CRC of the
un-stuffed packet so far; the whole packet is stuffed like any other.
"""
import json
import logging
import math
import threading
import time

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.paths import config_path
from snake_autonomy.sim.pty_serving import CONTROL_COMMANDS, MockBusClient, PtyServing  # noqa: F401 (API)
from snake_autonomy.sim.servo_backend import ServoBackend

DEFAULT_TABLE = config_path("dynamixel", "xh540_w270.yaml")
MEMORY_BYTES = 1024
LOG = logging.getLogger(__name__)
FAULT_KINDS = ("corrupt_crc", "drop_reply", "truncate_reply", "garbage_before")
INSTRUCTION_NAMES = {
    dx.instruction.PING: "PING", dx.instruction.READ: "READ", dx.instruction.WRITE: "WRITE",
    dx.instruction.REBOOT: "REBOOT", dx.instruction.SYNC_READ: "SYNC_READ",
    dx.instruction.SYNC_WRITE: "SYNC_WRITE", dx.instruction.FAST_SYNC_READ: "FAST_SYNC_READ",
}
# Servo error numbers (status packet error byte, bits 0-6).
RESULT_FAIL, INSTRUCTION_ERROR, CRC_ERROR, DATA_RANGE_ERROR, DATA_LENGTH_ERROR, DATA_LIMIT_ERROR, ACCESS_ERROR = \
    1, 2, 3, 4, 5, 6, 7


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


class _Servo:
    def __init__(self, servo_id, table):
        self.id = servo_id
        self.memory = bytearray(MEMORY_BYTES)
        for e in table.entries:
            self.memory[e.address:e.address + e.size] = _pack(e.default, e.size, e.is_signed)
        idx = table.find("id")
        if idx is not None:
            self.memory[idx.address] = servo_id
        self.silent = False
        self.goal_writes = 0


def _pack(value: int, size: int, signed: bool) -> bytes:
    return int(value).to_bytes(size, "little", signed=signed and value < 0)


def _unpack(data, signed: bool) -> int:
    return int.from_bytes(bytes(data), "little", signed=signed)


def _read_error(address: int, length: int) -> int:
    """The servo error number of a read of `length` bytes at `address` (0: a legal read)."""
    if length == 0:
        return DATA_LENGTH_ERROR
    return DATA_RANGE_ERROR if address + length > MEMORY_BYTES else 0


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
        self._clock = clock
        self._lock = threading.RLock()
        self._servos = {i: _Servo(i, self.table) for i in ids}
        t = self.table
        self._e = {name: t.at(name) for name in (
            "torque_enable", "hardware_error_status", "goal_position", "present_current", "present_velocity",
            "present_position", "present_input_voltage", "present_temperature", "min_position_limit",
            "max_position_limit", "model_number", "firmware_version")}
        self._rad_per_tick = self._e["present_position"].scale * math.pi / 180.0
        self._rad_s_per_unit = self._e["present_velocity"].scale * 2.0 * math.pi / 60.0
        self._amps_per_unit = self._e["present_current"].scale * 1e-3
        self._centre = t.position_centre_ticks
        self._faults = []
        self._rx = bytearray()
        self.reset_stats()
        PtyServing.__init__(self)

    # ------------------------------------------------------------------------------------------
    # fault injection and inspection (thread-safe)
    def inject(self, kind: str, ids=None, count=None):
        """Damage the next `count` replies (None: until cleared) of `ids` (None: every servo)."""
        if kind not in FAULT_KINDS:
            raise ValueError(f"kind: {kind!r} is not one of {FAULT_KINDS}")
        if count is not None and (not isinstance(count, int) or count < 1):
            raise ValueError(f"count: {count!r} is not a positive integer or None")
        ids = None if ids is None else {self._check_id(i) for i in ids}
        with self._lock:
            self._faults.append({"kind": kind, "ids": ids, "remaining": count})

    def set_silent(self, servo_id: int, silent: bool = True):
        with self._lock:
            self._servos[self._check_id(servo_id)].silent = bool(silent)

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
            s = self._servos[self._check_id(servo_id)]
            s.memory[self._e["hardware_error_status"].address] = bits
            if bits:
                self._set_torque(s, False)  # the servo's shutdown

    def clear_faults(self):
        with self._lock:
            self._faults.clear()
            for s in self._servos.values():
                s.silent = False
                s.memory[self._e["hardware_error_status"].address] = 0

    def reset_stats(self):
        with self._lock:
            self._stats = {"packets": 0, "bad_packets": 0, "dropped": 0, "bytes_received": 0, "bytes_sent": 0,
                           "replies": 0, "replies_damaged": 0, "rejected_writes": 0, "superseded": 0,
                           "late_dropped": 0,
                           "instructions": {name: 0 for name in INSTRUCTION_NAMES.values()}}
            for s in self._servos.values():
                s.goal_writes = 0

    def stats(self) -> dict:
        """Counts of what the mock received and sent since start or reset_stats()."""
        with self._lock:
            out = json.loads(json.dumps(self._stats))
            out["goal_writes"] = {str(i): s.goal_writes for i, s in self._servos.items()}
            out["goal_writes_total"] = sum(s.goal_writes for s in self._servos.values())
            out["goal_ticks"] = {str(i): self._read_entry(s, "goal_position") for i, s in self._servos.items()}
            return out

    def state(self) -> dict:
        """Per servo: goal and present ticks, torque, hardware error bits, Return Delay Time."""
        with self._lock:
            self._refresh()
            return {str(i): {"goal_ticks": self._read_entry(s, "goal_position"),
                             "present_ticks": self._read_entry(s, "present_position"),
                             "torque": bool(self._read_entry(s, "torque_enable")),
                             "hardware_error": self._read_entry(s, "hardware_error_status"),
                             "return_delay_us": 2 * self._read_entry(s, "return_delay_time"),
                             "silent": s.silent}
                    for i, s in self._servos.items()}

    def _check_id(self, servo_id) -> int:
        if servo_id not in self._servos:
            raise ValueError(f"id: {servo_id!r} is not on this bus ({sorted(self._servos)})")
        return servo_id

    # ------------------------------------------------------------------------------------------
    # protocol: bytes in, bytes out (usable without a pty)
    def _clear_input(self):
        self._rx.clear()

    def _late_dropped(self):  # (called with _lock held)
        self._stats["late_dropped"] += 1

    def handle(self, data: bytes, latest_only: bool = False) -> bytes:
        """Feed received bytes; returns the bytes the servos send back. latest_only (the pty): when
        several packets came in one read, the master sent the later ones after giving up on the
        earlier ones, so only the last packet is answered (a real servo's late answer would have
        collided with them); the earlier ones still act (writes are applied), counted as superseded."""
        out = bytearray()
        with self._lock:
            self._stats["bytes_received"] += len(data)
            self._rx += data
            while self._rx:
                status, consumed, _start, pid, inst, params = dx.parse_packet(bytes(self._rx))
                if status == dx.ParseStatus.INCOMPLETE:
                    del self._rx[:consumed]
                    break
                del self._rx[:consumed]
                if status != dx.ParseStatus.OK:
                    self._stats["bad_packets"] += 1
                else:
                    self._stats["packets"] += 1
                if latest_only and out:  # a later packet followed: the master gave up on this answer
                    self._stats["superseded"] += 1
                    out.clear()
                out += self._answer(status, pid, inst, params)
            self._stats["bytes_sent"] += len(out)
        return bytes(out)

    def _answer(self, status, pid, inst, params) -> bytes:
        """The reply to one parsed packet. The last-resort guard: an exception nobody foresaw costs
        this packet (no reply, counted as dropped, logged), never the bus."""
        try:
            if status == dx.ParseStatus.OK:
                return self._dispatch(pid, inst, params)
            if status == dx.ParseStatus.BAD_CRC and pid in self._servos:
                return self._reply(self._servos[pid], CRC_ERROR, b"")  # the servo it names says so
            return b""  # broadcast, not ours, or no trustworthy ID (malformed): silence
        except Exception as exc:  # noqa: BLE001 - on purpose, see the docstring
            self._stats["dropped"] += 1
            name = INSTRUCTION_NAMES.get(inst, f"instruction {inst!r}")
            LOG.error("mock servo bus: dropped %s to ID %s (%s parameter bytes %s): %s: %s", name, pid,
                      len(params or b""), bytes(params or b"")[:16].hex(" "), type(exc).__name__, exc)
            return b""

    def _dispatch(self, pid, inst, params) -> bytes:
        name = INSTRUCTION_NAMES.get(inst)
        if name:
            self._stats["instructions"][name] += 1
        if inst == dx.instruction.STATUS:
            return b""  # another device's status packet (or an echo): not for us
        broadcast = pid == dx.BROADCAST_ID
        if not broadcast and pid not in self._servos:
            return b""
        u16 = lambda i: params[i] | (params[i + 1] << 8)  # noqa: E731
        if inst == dx.instruction.PING:
            ids = sorted(self._servos) if broadcast else [pid]
            return b"".join(self._reply(self._servos[i], 0, self._ping_data(self._servos[i])) for i in ids)
        if inst in (dx.instruction.SYNC_READ, dx.instruction.FAST_SYNC_READ, dx.instruction.SYNC_WRITE):
            if not broadcast or len(params) < 4:
                return b""
            address, length = u16(0), u16(2)
            if inst == dx.instruction.SYNC_WRITE:
                body = params[4:]
                for k in range(0, len(body) - length, 1 + length):
                    s = self._servos.get(body[k])
                    if s is not None and self._write(s, address, body[k + 1:k + 1 + length]):
                        self._stats["rejected_writes"] += 1
                return b""
            self._refresh()
            ids = [i for i in params[4:] if i in self._servos]
            if inst == dx.instruction.SYNC_READ:
                err = _read_error(address, length)
                return b"".join(self._reply(s, err, b"" if err else self._read(s, address, length))
                                for s in (self._servos[i] for i in ids))
            return self._fast_reply([self._servos[i] for i in ids], address, length)
        if inst == dx.instruction.WRITE and len(params) < 3:
            return b"" if broadcast else self._reply(self._servos[pid], DATA_LENGTH_ERROR, b"")
        if inst == dx.instruction.WRITE:
            targets = list(self._servos.values()) if broadcast else [self._servos[pid]]
            for s in targets:
                err = self._write(s, u16(0), params[2:])
                if err:
                    self._stats["rejected_writes"] += 1
            return b"" if broadcast else self._reply(targets[0], err, b"")
        if broadcast:
            return b""
        s = self._servos[pid]
        if inst == dx.instruction.READ:
            if len(params) != 4:
                return self._reply(s, DATA_LENGTH_ERROR, b"")
            address, length = u16(0), u16(2)
            if _read_error(address, length):
                return self._reply(s, _read_error(address, length), b"")
            self._refresh()
            return self._reply(s, 0, self._read(s, address, length))
        if inst == dx.instruction.REBOOT:
            reply = self._reply(s, 0, b"")  # the servo answers, then restarts
            s.memory[self._e["hardware_error_status"].address] = 0
            self._set_torque(s, False)
            return reply
        return self._reply(s, INSTRUCTION_ERROR, b"")

    def _ping_data(self, s) -> bytes:
        return bytes(s.memory[0:2]) + bytes([s.memory[self._e["firmware_version"].address]])

    def _alert(self, s) -> int:
        return dx.ALERT_BIT if s.memory[self._e["hardware_error_status"].address] else 0

    def _read(self, s, address, length) -> bytes:
        return bytes(s.memory[address:address + length])

    def _read_entry(self, s, name) -> int:
        e = self._e.get(name) or self.table.at(name)
        return _unpack(s.memory[e.address:e.address + e.size], e.is_signed)

    def _write_entry(self, s, name, value):
        e = self._e[name]
        lo, hi = (-(1 << (8 * e.size - 1)), (1 << (8 * e.size - 1)) - 1) if e.is_signed else (0, (1 << (8 * e.size)) - 1)
        s.memory[e.address:e.address + e.size] = _pack(max(lo, min(hi, value)), e.size, e.is_signed)

    def _set_torque(self, s, on: bool):
        s.memory[self._e["torque_enable"].address] = 1 if on else 0
        self.backend.set_torque(s.id, on)

    def _write(self, s, address, data) -> int:
        """Applies a write, all or nothing; returns the servo error number (0: accepted)."""
        end = address + len(data)
        if end > MEMORY_BYTES or not data:
            return DATA_RANGE_ERROR
        torque_on = s.memory[self._e["torque_enable"].address] != 0
        values = {}
        for e in self.table.entries:
            if e.address + e.size <= address or e.address >= end:
                continue
            if not e.writable or (e.eeprom and torque_on):
                return ACCESS_ERROR
            if e.address < address or e.address + e.size > end:
                return DATA_LENGTH_ERROR
            v = _unpack(data[e.address - address:e.address - address + e.size], e.is_signed)
            if e.has_range and not e.min <= v <= e.max:
                return DATA_LIMIT_ERROR
            values[e.name] = v
        if "goal_position" in values:
            lo, hi = self._read_entry(s, "min_position_limit"), self._read_entry(s, "max_position_limit")
            if not lo <= values["goal_position"] <= hi:
                return DATA_LIMIT_ERROR
        if values.get("torque_enable") and s.memory[self._e["hardware_error_status"].address]:
            return RESULT_FAIL  # no torque while a hardware error stands
        self.backend.advance(self._clock())
        s.memory[address:end] = data
        if "torque_enable" in values:
            self._set_torque(s, bool(values["torque_enable"]))
        if "goal_position" in values:
            s.goal_writes += 1
            self.backend.set_goal(s.id, (values["goal_position"] - self._centre) * self._rad_per_tick)
        return 0

    def _refresh(self):
        """Present position, velocity, current, voltage, temperature from the backend."""
        self.backend.advance(self._clock())
        for s in self._servos.values():
            st = self.backend.state(s.id)
            self._write_entry(s, "present_position", round(st.position_rad / self._rad_per_tick) + self._centre)
            self._write_entry(s, "present_velocity", round(st.velocity_rad_s / self._rad_s_per_unit))
            self._write_entry(s, "present_current", round(st.current_a / self._amps_per_unit))
            self._write_entry(s, "present_input_voltage", round(st.voltage_v / self._e["present_input_voltage"].scale))
            self._write_entry(s, "present_temperature", round(st.temperature_c))

    # ------------------------------------------------------------------------------------------
    # replies and their faults
    def _take_faults(self, ids) -> list:
        kinds = []
        for f in list(self._faults):
            if f["ids"] is not None and not f["ids"] & set(ids):
                continue
            kinds.append(f["kind"])
            if f["remaining"] is not None:
                f["remaining"] -= 1
                if f["remaining"] <= 0:
                    self._faults.remove(f)
        return kinds

    def _damage(self, packet: bytes, ids) -> bytes:
        kinds = self._take_faults(ids)
        if not kinds:
            return packet
        self._stats["replies_damaged"] += 1
        if "drop_reply" in kinds:
            return b""
        if "corrupt_crc" in kinds:
            packet = packet[:-1] + bytes([packet[-1] ^ 0xFF])
        if "truncate_reply" in kinds:
            packet = packet[:max(5, len(packet) // 2)]
        if "garbage_before" in kinds:
            packet = b"\x00\x13\xff\xff\xfd\xfd" + packet
        return packet

    def _reply(self, s, error: int, data: bytes) -> bytes:
        if s.silent:
            return b""
        self._stats["replies"] += 1
        return self._damage(dx.encode_status(s.id, error | self._alert(s), data), [s.id])

    def _fast_reply(self, servos, address, length) -> bytes:
        servos = [s for s in servos if not s.silent]
        if not servos:
            return b""
        self._stats["replies"] += 1
        if dx.STATUS_OVERHEAD + len(servos) * (length + 4) > dx.MAX_PACKET_BYTES:  # as Protocol2Bus checks
            # More than one packet can carry (before stuffing): the servos refuse it.
            return self._damage(dx.encode_status(dx.BROADCAST_ID, DATA_LENGTH_ERROR, b""), [s.id for s in servos])
        err = _read_error(address, length)
        # The un-stuffed packet: header, ID, LEN, INST, then ERR ID DATA CRC per servo.
        n_params = len(servos) * (length + 4) - 2
        raw = bytearray(b"\xff\xff\xfd\x00" + bytes([dx.BROADCAST_ID]) + (n_params + 3).to_bytes(2, "little") + b"\x55")
        for k, s in enumerate(servos):
            if k:
                raw += dx.crc16(bytes(raw)).to_bytes(2, "little")
            data = bytes(length) if err else self._read(s, address, length)
            raw += bytes([err | self._alert(s), s.id]) + data
        try:
            packet = dx.encode_status(dx.BROADCAST_ID, raw[8], bytes(raw[9:]))
        except ValueError:  # it fitted before stuffing, not after
            packet = dx.encode_status(dx.BROADCAST_ID, DATA_LENGTH_ERROR, b"")
        return self._damage(packet, [s.id for s in servos])
