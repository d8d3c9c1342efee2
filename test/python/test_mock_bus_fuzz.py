"""The mocked servo bus never dies: every legal packet gets its answer or the servo's error status,
damaged packets get a CRC error or silence, and a fixed-seed corpus of random and mutated packets
(every instruction; bit flips, truncation, insertion, length lies, stuffing breaks, garbage)
never raises out of its dispatch, never needs the last-resort guard, and leaves it answering PING."""
import logging
import random
import time

import pytest

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.sim.mock_servo_bus import MockServoBus
from snake_autonomy.sim.servo_model import KinematicServoBackend

IDS = list(range(1, 12))
I = dx.instruction
INSTRUCTIONS = [I.PING, I.READ, I.WRITE, I.REBOOT, I.SYNC_READ, I.SYNC_WRITE, I.FAST_SYNC_READ, I.STATUS]
RESULT_FAIL, INSTRUCTION_ERROR, CRC_ERROR, DATA_RANGE_ERROR, DATA_LENGTH_ERROR = 1, 2, 3, 4, 5


@pytest.fixture
def mock():
    return MockServoBus(KinematicServoBackend(IDS), IDS)


def statuses(reply: bytes) -> list:
    """Every status packet in `reply` as (id, error, data); fails unless `reply` is exactly that."""
    out = []
    while reply:
        st, consumed, start, pid, inst, params = dx.parse_packet(reply)
        assert st == dx.ParseStatus.OK and start == 0, f"{st} in reply {reply[:40].hex(' ')}"
        assert inst == I.STATUS and len(params) >= 1
        out.append((pid, params[0], params[1:]))
        reply = reply[consumed:]
    return out


def u16(v: int) -> bytes:
    return (v & 0xFFFF).to_bytes(2, "little")


def answers_ping(mock, servo_id=3) -> bool:
    """The PING is answered last; before it may come the CRC error of a damaged packet whose end
    the mock could only judge when the PING's first bytes arrived."""
    replies = [(p, e) for p, e, _ in statuses(mock.handle(dx.encode_packet(servo_id, I.PING)))]
    return replies[-1:] == [(servo_id, 0)] and all(e == CRC_ERROR for _, e in replies[:-1])


# ---------------------------------------------------------------------------------------------
# the packets that killed it, and the error statuses it owes
def test_fast_sync_read_too_long_for_one_packet_answers_data_length_error(mock):
    request = dx.encode_packet(dx.BROADCAST_ID, I.FAST_SYNC_READ, u16(0) + u16(200) + bytes(IDS))
    assert statuses(mock.handle(request)) == [(dx.BROADCAST_ID, DATA_LENGTH_ERROR, b"")]
    assert answers_ping(mock)
    # One that fits is answered in full: ERR ID DATA CRC per servo.
    length = 100
    (pid, err, data), = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, I.FAST_SYNC_READ,
                                                              u16(0) + u16(length) + bytes(IDS))))
    assert (pid, err, len(data)) == (dx.BROADCAST_ID, 0, len(IDS) * (length + 4) - 3)


def test_reads_beyond_the_control_table_answer_data_range_error(mock):
    beyond = u16(1000) + u16(100)
    assert statuses(mock.handle(dx.encode_packet(2, I.READ, beyond))) == [(2, DATA_RANGE_ERROR, b"")]
    replies = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, I.SYNC_READ, beyond + bytes([1, 2]))))
    assert replies == [(1, DATA_RANGE_ERROR, b""), (2, DATA_RANGE_ERROR, b"")]
    (pid, err, data), = statuses(mock.handle(dx.encode_packet(dx.BROADCAST_ID, I.FAST_SYNC_READ,
                                                              u16(65535) + u16(4) + bytes([1, 2]))))
    assert pid == dx.BROADCAST_ID and err == DATA_RANGE_ERROR  # each block's error byte too
    assert (data[0], data[7], data[8]) == (1, DATA_RANGE_ERROR, 2)  # ID1 DATA(4) CRC(2) ERR2 ID2
    assert answers_ping(mock)


def test_wrong_parameter_counts_answer_data_length_error(mock):
    assert statuses(mock.handle(dx.encode_packet(2, I.READ, b"\x84\x00\x04")))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, I.READ, u16(132) + u16(0))))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, I.WRITE, b"\x40")))[0][1] == DATA_LENGTH_ERROR
    assert statuses(mock.handle(dx.encode_packet(2, 0x10)))[0][1] == INSTRUCTION_ERROR  # unknown instruction
    assert mock.handle(dx.encode_packet(dx.BROADCAST_ID, I.SYNC_READ, b"\x84")) == b""  # broadcast: no reply
    assert answers_ping(mock)


def test_bad_crc_to_one_servo_answers_crc_error_broadcast_stays_silent(mock):
    bad = bytearray(dx.encode_packet(4, I.READ, u16(132) + u16(4)))
    bad[-1] ^= 0x55
    assert statuses(mock.handle(bytes(bad))) == [(4, CRC_ERROR, b"")]
    bad_broadcast = bytearray(dx.encode_packet(dx.BROADCAST_ID, I.PING))
    bad_broadcast[-2] ^= 0x01
    assert mock.handle(bytes(bad_broadcast)) == b""
    not_ours = bytearray(dx.encode_packet(99, I.PING))
    not_ours[-2] ^= 0x01
    assert mock.handle(bytes(not_ours)) == b""
    assert mock.stats()["bad_packets"] == 3


def test_guard_turns_an_unexpected_exception_into_a_counted_drop(mock, monkeypatch, caplog):
    def boom(*_):
        raise ZeroDivisionError("injected")

    monkeypatch.setattr(mock, "_refresh", boom)
    read = dx.encode_packet(5, I.READ, u16(132) + u16(4))
    with caplog.at_level(logging.ERROR, logger="snake_autonomy.sim.mock_servo_bus"):
        assert mock.handle(read + dx.encode_packet(6, I.WRITE, u16(65) + b"\x01")) != b""  # the WRITE is answered
    assert mock.stats()["dropped"] == 1
    assert any("ZeroDivisionError" in r.getMessage() and "READ" in r.getMessage() for r in caplog.records)
    monkeypatch.undo()
    assert answers_ping(mock)


# ---------------------------------------------------------------------------------------------
# the fuzz
def legal_packet(rng: random.Random) -> bytes:
    inst = rng.choice(INSTRUCTIONS + [rng.randrange(256)])
    pid = rng.choice(IDS + IDS + [dx.BROADCAST_ID, dx.BROADCAST_ID, 0, 200])
    if inst in (I.SYNC_READ, I.SYNC_WRITE, I.FAST_SYNC_READ) and rng.random() < 0.9:
        pid = dx.BROADCAST_ID  # as they are meant to be sent
    address = rng.choice([rng.randrange(0, 150), rng.randrange(0, 1100), rng.randrange(65536)])
    length = rng.choice([0, 1, 2, 4, 10, rng.randrange(0, 300), rng.randrange(65536)])
    ids = bytes(rng.sample(IDS, rng.randint(1, 11)) if rng.random() < 0.8 else
                [rng.randrange(256) for _ in range(rng.randint(0, 20))])
    if inst == I.READ:
        params = u16(address) + u16(length)
    elif inst == I.WRITE:
        params = u16(address) + bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 2, 4, rng.randrange(40)])))
    elif inst in (I.SYNC_READ, I.FAST_SYNC_READ):
        params = u16(address) + u16(length) + ids
    elif inst == I.SYNC_WRITE:
        length = rng.choice([1, 2, 4, rng.randrange(0, 12)])
        params = u16(address) + u16(length) + b"".join(bytes([i]) + bytes(rng.randrange(256) for _ in range(length))
                                                       for i in ids)
    else:
        params = bytes(rng.randrange(256) for _ in range(rng.choice([0, 0, 1, 3, rng.randrange(60)])))
    if rng.random() < 0.1:
        params = params[:rng.randrange(len(params) + 1)]  # too short for its instruction
    return dx.encode_packet(pid, inst, params)


def mutate(pkt: bytes, rng: random.Random) -> bytes:
    b = bytearray(pkt)
    kind = rng.randrange(6)
    if kind == 0:
        for _ in range(rng.randint(1, 3)):
            b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)
    elif kind == 1:
        if rng.random() < 0.5:
            del b[rng.randrange(len(b))]
        else:
            del b[rng.randrange(1, len(b)):]
    elif kind == 2:
        for _ in range(rng.randint(1, 3)):
            b.insert(rng.randrange(len(b) + 1), rng.randrange(256))
    elif kind == 3:
        b[5:7] = u16(rng.randrange(65536))
        if rng.random() < 0.5:
            b[-2:] = dx.crc16(bytes(b[:-2])).to_bytes(2, "little")
    elif kind == 4:  # FF FF FD without its stuffed FD, under a valid CRC
        at = rng.randrange(8, len(b) - 1)
        b[at:at] = b"\xff\xff\xfd"
        if at + 3 < len(b) - 2 and b[at + 3] == 0xFD:
            b[at + 3] = 0x01
        b[5:7] = u16(len(b) - 7)
        b[-2:] = dx.crc16(bytes(b[:-2])).to_bytes(2, "little")
    else:
        b[0:0] = bytes(rng.choice([0x00, 0xFF, 0xFD, rng.randrange(256)]) for _ in range(rng.randint(1, 12)))
    return bytes(b)


def test_fuzz_dispatch_fixed_seed_never_raises_and_keeps_answering(mock):
    rng = random.Random(20261201)
    n_inputs, replies, start = 4000, 0, time.monotonic()
    for k in range(n_inputs):
        pkt = legal_packet(rng)
        data = pkt if rng.random() < 0.4 else mutate(pkt, rng)
        # Delivered in one read or in small pieces, as a pty hands them over.
        cut = sorted(rng.sample(range(1, len(data)), min(len(data) - 1, rng.randint(0, 3))))
        reply = b"".join(mock.handle(data[a:b]) for a, b in zip([0] + cut, cut + [len(data)]))
        for pid, err, _ in statuses(reply):  # a reply is whole status packets, or nothing
            assert pid in IDS or pid == dx.BROADCAST_ID
            replies += 1
        if k % 10 == 0 or data != pkt:
            assert answers_ping(mock, IDS[k % len(IDS)]), f"input {k} ({data[:40].hex(' ')}) left the mock deaf"
    stats = mock.stats()
    assert stats["dropped"] == 0  # the guard was never needed: every packet handled on purpose
    assert replies > n_inputs // 4
    print(f"mock dispatch fuzz: {n_inputs} inputs, {replies} status packets, {stats['bad_packets']} bad packets, "
          f"0 exceptions, {time.monotonic() - start:.1f} s")
