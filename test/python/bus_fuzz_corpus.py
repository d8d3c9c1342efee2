"""A fixed-seed corpus for fuzzing the mocked servo bus's dispatch: legal packets of every
instruction (and unknown ones) with random addresses, lengths, IDs and parameter counts, and their
mutations (bit flips, truncation, insertion, length lies, stuffing breaks under a valid CRC,
garbage prefixes). Used by test_mock_bus_fuzz.py (bounded, in CI) and bench/fuzz_mock_bus (long)."""
import random

from snake_autonomy._core import dynamixel as dx
from snake_autonomy.sim.mock_servo_bus import CRC_ERROR

IDS = list(range(1, 12))
INST = dx.instruction
INSTRUCTIONS = [INST.PING, INST.READ, INST.WRITE, INST.REBOOT, INST.SYNC_READ, INST.SYNC_WRITE, INST.FAST_SYNC_READ,
                INST.STATUS]


def u16(v: int) -> bytes:
    return (v & 0xFFFF).to_bytes(2, "little")


def statuses(reply: bytes) -> list:
    """Every status packet in `reply` as (id, error, data); AssertionError unless `reply` is exactly that."""
    out = []
    while reply:
        st, consumed, start, pid, inst, params = dx.parse_packet(reply)
        assert st == dx.ParseStatus.OK and start == 0, f"{st} in reply {reply[:40].hex(' ')}"
        assert inst == INST.STATUS and len(params) >= 1, f"not a status packet: {reply[:40].hex(' ')}"
        out.append((pid, params[0], params[1:]))
        reply = reply[consumed:]
    return out


def answers_ping(mock, servo_id=3) -> bool:
    """The PING is answered last; before it may come the CRC error of a damaged packet whose end
    the mock could only judge when the PING's first bytes arrived."""
    replies = [(p, e) for p, e, _ in statuses(mock.handle(dx.encode_packet(servo_id, INST.PING)))]
    return replies[-1:] == [(servo_id, 0)] and all(e == CRC_ERROR for _, e in replies[:-1])


def legal_packet(rng: random.Random) -> bytes:
    inst = rng.choice(INSTRUCTIONS + [rng.randrange(256)])
    pid = rng.choice(IDS + IDS + [dx.BROADCAST_ID, dx.BROADCAST_ID, 0, 200])
    if inst in (INST.SYNC_READ, INST.SYNC_WRITE, INST.FAST_SYNC_READ) and rng.random() < 0.9:
        pid = dx.BROADCAST_ID  # as they are meant to be sent
    address = rng.choice([rng.randrange(0, 150), rng.randrange(0, 1100), rng.randrange(65536)])
    length = rng.choice([0, 1, 2, 4, 10, rng.randrange(0, 300), rng.randrange(65536)])
    ids = bytes(rng.sample(IDS, rng.randint(1, 11)) if rng.random() < 0.8 else
                [rng.randrange(256) for _ in range(rng.randint(0, 20))])
    if inst == INST.READ:
        params = u16(address) + u16(length)
    elif inst == INST.WRITE:
        params = u16(address) + bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 2, 4, rng.randrange(40)])))
    elif inst in (INST.SYNC_READ, INST.FAST_SYNC_READ):
        params = u16(address) + u16(length) + ids
    elif inst == INST.SYNC_WRITE:
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


def run(mock, n_inputs: int, seed: int, ping_every: int = 10) -> dict:
    """Feeds n_inputs packets (40 % legal, 60 % mutated) to mock.handle in random chunks. Raises
    AssertionError when a reply is not whole status packets from our IDs, or when a PING goes
    unanswered after a damaged input (and every `ping_every` inputs). Returns the counts."""
    rng = random.Random(seed)
    replies = collisions = 0
    for k in range(n_inputs):
        pkt = legal_packet(rng)
        data = pkt if rng.random() < 0.4 else mutate(pkt, rng)
        # Delivered in one read or in small pieces, as a pty hands them over.
        cut = sorted(rng.sample(range(1, len(data)), min(len(data) - 1, rng.randint(0, 3))))
        reply = b"".join(mock.handle(data[a:b]) for a, b in zip([0] + cut, cut + [len(data)]))
        for pid, _err, _data in statuses(reply):  # a reply is whole status packets, or nothing
            assert pid in IDS or pid == dx.BROADCAST_ID, f"input {k}: reply from ID {pid}"
            replies += 1
        if k % ping_every == 0 or data != pkt:
            servo_id = IDS[k % len(IDS)]
            pending = mock.servos.pending_input()  # what the mock holds, undecided, before the PING
            if not answers_ping(mock, servo_id):
                # Allowed only when the bytes themselves are ambiguous: the pending bytes and the
                # PING's first ones form a span with a valid CRC (e.g. a packet that lost its last
                # byte, FF, completed by the PING's first FF: the same bytes as an intact packet
                # followed by a PING that lost its first byte). A second PING must be answered.
                st, consumed, *_ = dx.parse_packet(pending + dx.encode_packet(servo_id, INST.PING))
                assert st == dx.ParseStatus.OK and consumed > len(pending), \
                    f"input {k} ({data[:40].hex(' ')}) left the mock deaf"
                collisions += 1
                assert answers_ping(mock, servo_id), f"input {k} ({data[:40].hex(' ')}) left the mock deaf"
    return {"inputs": n_inputs, "status_packets": replies, "crc_collisions": collisions}
