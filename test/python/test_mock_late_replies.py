"""The mocked bus on a loaded machine answers like a real servo: within its return delay or not at
all. When this (Python) process was slow and the master has already sent its next packet, the late
answer is dropped instead of being sent into the next transaction, where the driver could take it
for the next request's reply."""
import os
import select
import struct

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.sim.mock_servo_bus import MockServoBus
from snake_autonomy.sim.servo_model import KinematicServoBackend, KinematicServoParams

READ = dx.instruction.READ


def read_request(servo_id, address, length):
    return dx.encode_packet(servo_id, READ, struct.pack("<HH", address, length))


def statuses(data: bytes):
    out = []
    while data:
        st, consumed, _, pid, _inst, params = dx.parse_packet(data)
        assert st == dx.ParseStatus.OK, st
        out.append((pid, params[0], params[1:]))
        data = data[consumed:]
    return out


def make_mock():
    return MockServoBus(KinematicServoBackend([1, 2], KinematicServoParams()), [1, 2])


def test_handle_answers_every_packet_unless_latest_only():
    mock = make_mock()
    two = read_request(1, 11, 1) + read_request(2, 9, 1)  # operating mode of 1, return delay of 2
    assert [(p, d) for p, _, d in statuses(mock.handle(two))] == [(1, b"\x03"), (2, b"\xfa")]
    assert mock.stats()["superseded"] == 0
    # The pty's rule: both came in one read, so the first was given up by the master.
    assert [(p, d) for p, _, d in statuses(mock.handle(two, latest_only=True))] == [(2, b"\xfa")]
    assert mock.stats()["superseded"] == 1


def read_available(fd, timeout_s):
    """Everything readable on fd within timeout_s of the first byte (b"" if nothing came)."""
    out = b""
    while select.select([fd], [], [], timeout_s if not out else 0.05)[0]:
        chunk = os.read(fd, 4096)
        if not chunk:
            break
        out += chunk
    return out


def test_pty_drops_a_reply_when_the_next_request_is_already_waiting(tmp_path):
    mock = make_mock()
    mock.open_pty(str(tmp_path / "bus"))  # no serving thread: _serve_pty is driven by hand
    master, slave = mock._master, mock._slave
    try:
        os.set_blocking(slave, False)
        real_handle = mock.handle

        def slow_handle(data, latest_only=False):
            # The master gives up while the mock computes the answer and sends its next request.
            os.write(slave, read_request(2, 9, 1))
            return real_handle(data, latest_only)

        os.write(slave, read_request(1, 11, 1))
        mock.handle = slow_handle
        mock._serve_pty(master)
        assert read_available(slave, 0.2) == b"", "a reply to a request the master gave up on was sent"
        assert mock.stats()["late_dropped"] == 1
        # The next request (already waiting) is answered normally: the master gets its own reply.
        mock.handle = real_handle
        mock._serve_pty(master)
        assert [(p, d) for p, _, d in statuses(read_available(slave, 2.0))] == [(2, b"\xfa")]
        assert mock.stats()["late_dropped"] == 1
    finally:
        mock.close_pty()
