"""The mocked servo bus never dies: every legal packet gets its answer or the servo's error status,
damaged packets get a CRC error or silence, and a fixed-seed corpus of random and mutated packets
(every instruction; bit flips, truncation, insertion, length lies, stuffing breaks, garbage)
never raises out of its dispatch, never needs the last-resort guard, and leaves it answering PING.
Its control socket refuses bad commands without ending the serving loop."""
import json
import logging
import socket
import time

import pytest

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.sim.mock_servo_bus import (CRC_ERROR, DATA_LENGTH_ERROR, DATA_RANGE_ERROR, INSTRUCTION_ERROR,
                                                MockBusClient, MockServoBus)
from snake_autonomy.sim.servo_model import KinematicServoBackend

import bus_fuzz_corpus
from bus_fuzz_corpus import IDS, INST, answers_ping, statuses, u16


@pytest.fixture
def mock():
    return MockServoBus(KinematicServoBackend(IDS), IDS)


# ---------------------------------------------------------------------------------------------
# the packets that killed it, and the error statuses it owes
def test_fast_sync_read_too_long_for_one_packet_answers_data_length_error(mock):
    request = dx.encode_packet(dx.BROADCAST_ID, INST.FAST_SYNC_READ, u16(0) + u16(200) + bytes(IDS))
    assert statuses(mock.handle(request)) == [(dx.BROADCAST_ID, DATA_LENGTH_ERROR, b"")]
    assert answers_ping(mock)
    # One that fits is answered in full: ERR ID DATA CRC per servo.
    length = 100
    (pid, err, data), = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, INST.FAST_SYNC_READ,
                                                              u16(0) + u16(length) + bytes(IDS))))
    assert (pid, err, len(data)) == (dx.BROADCAST_ID, 0, len(IDS) * (length + 4) - 3)


def test_reads_beyond_the_control_table_answer_data_range_error(mock):
    beyond = u16(1000) + u16(100)
    assert statuses(mock.handle(dx.encode_packet(2, INST.READ, beyond))) == [(2, DATA_RANGE_ERROR, b"")]
    replies = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, INST.SYNC_READ, beyond + bytes([1, 2]))))
    assert replies == [(1, DATA_RANGE_ERROR, b""), (2, DATA_RANGE_ERROR, b"")]
    (pid, err, data), = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, INST.FAST_SYNC_READ,
                                                              u16(65535) + u16(4) + bytes([1, 2]))))
    assert pid == dx.BROADCAST_ID and err == DATA_RANGE_ERROR  # each block's error byte too
    assert (data[0], data[7], data[8]) == (1, DATA_RANGE_ERROR, 2)  # ID1 DATA(4) CRC(2) ERR2 ID2
    assert answers_ping(mock)


def test_wrong_parameter_counts_answer_data_length_error(mock):
    assert statuses(mock.handle(dx.encode_packet(2, INST.READ, b"\x84\x00\x04")))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, INST.READ, u16(132) + u16(0))))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, INST.WRITE, b"\x40")))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, 0x10)))[0][1] == INSTRUCTION_ERROR  # unknown instruction
    assert mock.handle(dx.encode_packet(dx.BROADCAST_ID, INST.SYNC_READ, b"\x84")) == b""  # broadcast: no reply
    assert answers_ping(mock)


def test_bad_crc_to_one_servo_answers_crc_error_broadcast_stays_silent(mock):
    bad = bytearray(dx.encode_packet(4, INST.READ, u16(132) + u16(4)))
    bad[-1] ^= 0x55
    assert statuses(mock.handle(bytes(bad))) == [(4, CRC_ERROR, b"")]
    bad_broadcast = bytearray(dx.encode_packet(dx.BROADCAST_ID, INST.PING))
    bad_broadcast[-2] ^= 0x01
    assert mock.handle(bytes(bad_broadcast)) == b""
    not_ours = bytearray(dx.encode_packet(99, INST.PING))
    not_ours[-2] ^= 0x01
    assert mock.handle(bytes(not_ours)) == b""
    assert mock.stats()["bad_packets"] == 3


def test_guard_turns_an_unexpected_exception_into_a_counted_drop(mock, monkeypatch, caplog):
    def boom(*_):
        raise ZeroDivisionError("injected")

    monkeypatch.setattr(mock.backend, "state", boom)  # the backend fails while the servos refresh for a READ
    read = dx.encode_packet(5, INST.READ, u16(132) + u16(4))
    with caplog.at_level(logging.ERROR, logger="snake_autonomy.sim.mock_servo_bus"):
        reply = mock.handle(read + dx.encode_packet(6, INST.WRITE, u16(65) + b"\x01"))
    assert [pid for pid, _err, _data in statuses(reply)] == [5, 6]  # both answered (the READ with the last values)
    assert mock.stats()["dropped"] == 1
    assert any("ZeroDivisionError" in r.getMessage() and "before_read" in r.getMessage() for r in caplog.records)
    monkeypatch.undo()
    assert answers_ping(mock)


def test_control_commands_that_are_not_objects_are_refused_not_fatal(mock):
    for line in ("[1, 2]", '"stats"', "3", "null", '{"cmd": ["stats"]}', '{"cmd": "inject", "kind": "corrupt_crc", '
                 '"ids": [[1]]}', '{"cmd": "set_hardware_error", "id": 1, "bits": 1.5}', "{", "\udcff"):
        reply = mock.control(line)
        assert reply["ok"] is False and reply["error"], line
    assert mock.control('{"cmd": "stats"}')["ok"]
    assert answers_ping(mock)


def test_control_socket_survives_garbage_and_vanishing_clients(tmp_path):
    ctl = str(tmp_path / "bus.ctl")
    mock = MockServoBus(KinematicServoBackend(IDS), IDS).start(str(tmp_path / "bus"), ctl)
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as raw:
            raw.settimeout(5.0)
            raw.connect(ctl)
            raw.sendall(b"\xff\xfe{\n3\n")  # not UTF-8, then not an object
            buf = b""
            while buf.count(b"\n") < 2:
                chunk = raw.recv(4096)
                assert chunk, "the mock closed the control socket"
                buf += chunk
            assert [json.loads(x)["ok"] for x in buf.splitlines()] == [False, False]
            raw.sendall(b'{"cmd": "state"}\n')  # and goes away before the answer
        with MockBusClient(ctl) as client:
            assert client.call("stats")["dropped"] == 0
    finally:
        mock.stop()


# ---------------------------------------------------------------------------------------------
# the fuzz (the long run: bench/fuzz_mock_bus)
def test_fuzz_dispatch_fixed_seed_never_raises_and_keeps_answering(mock):
    start = time.monotonic()
    counts = bus_fuzz_corpus.run(mock, 4000, seed=20261201)
    stats = mock.stats()
    assert stats["dropped"] == 0  # the guard was never needed: every packet handled on purpose
    assert counts["status_packets"] > 1000 and stats["bad_packets"] > 1000
    assert counts["crc_collisions"] <= 1
    print(f"mock dispatch fuzz: {counts['inputs']} inputs, {counts['status_packets']} status packets, "
          f"{stats['bad_packets']} bad packets, 0 exceptions, {time.monotonic() - start:.1f} s")


def test_unstuff_binding_refuses_broken_stuffing():
    assert dx.unstuff(b"\x55\xff\xff\xfd\xfd\x01") == b"\x55\xff\xff\xfd\x01"
    with pytest.raises(ValueError, match="stuffed FD"):
        dx.unstuff(b"\x55\xff\xff\xfd\x01")
