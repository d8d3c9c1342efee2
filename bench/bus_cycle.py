#!/usr/bin/env python3
"""Bus cycle benchmark: our C++ SerialBus against ROBOTIS's Python SDK on the same mocked bus.

One cycle = sync read of the 10-byte feedback block at address 126 for every servo + sync write
of their goal positions. Prints bytes on the wire per cycle (against the ~325-byte minimum for
11 servos; less with fast sync read) and CPU time per cycle of each client process.

    scripts/with-env python3 bench/bus_cycle.py [--cycles 2000] [--ids 11]

Wall time per cycle here is dominated by the Python mock's reply time, not by either client.
"""
import argparse
import select
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def start_mock(link: str, n_ids: int):
    proc = subprocess.Popen([str(ROOT / "scripts" / "mock_servo_bus"), "--link", link, "--ids", f"1-{n_ids}"],
                            stdout=subprocess.PIPE, text=True)
    ready, _, _ = select.select([proc.stdout], [], [], 30.0)
    line = proc.stdout.readline().strip() if ready else ""
    if line != f"ready {link}":
        proc.kill()
        sys.exit(f"mock_servo_bus did not start (got {line!r})")
    return proc


def robotis_sdk_cycle(link: str, ids, cycles: int):
    """CPU and wall ms per cycle of ROBOTIS's SDK doing the same cycle (its own process)."""
    import dynamixel_sdk as sdk

    port = sdk.PortHandler(link)
    if not (port.openPort() and port.setBaudRate(1000000)):
        sys.exit("dynamixel_sdk could not open the port")
    ph = sdk.PacketHandler(2.0)
    reader = sdk.GroupSyncRead(port, ph, 126, 10)
    writer = sdk.GroupSyncWrite(port, ph, 116, 4)
    for i, sid in enumerate(ids):
        reader.addParam(sid)
        writer.addParam(sid, list((2048 + 20 * i).to_bytes(4, "little")))
    failed = 0
    for _ in range(20):
        reader.txRxPacket()
    c0, w0 = time.process_time(), time.monotonic()
    for _ in range(cycles):
        if reader.txRxPacket() != sdk.COMM_SUCCESS:
            failed += 1
        _ = [reader.getData(sid, 132, 4) for sid in ids]
        writer.txPacket()
    cpu_ms = (time.process_time() - c0) * 1e3 / cycles
    wall_ms = (time.monotonic() - w0) * 1e3 / cycles
    port.closePort()
    return cpu_ms, wall_ms, failed


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=2000)
    ap.add_argument("--ids", type=int, default=11)
    args = ap.parse_args()
    binary = ROOT / ".ws" / "devel" / "lib" / "snake_autonomy" / "bench_bus_cycle"
    if not binary.exists():
        sys.exit(f"{binary} is missing: run make build")
    with tempfile.TemporaryDirectory() as tmp:
        link = f"{tmp}/ttySNAKE"
        mock = start_mock(link, args.ids)
        try:
            out = subprocess.run([str(binary), "--port", link, "--ids", str(args.ids), "--cycles", str(args.cycles)],
                                 capture_output=True, text=True, timeout=600)
            print(out.stdout, end="")
            if out.returncode != 0:
                print(out.stderr, file=sys.stderr)
            cpp_cpu = float(out.stdout.split("cpu ")[1].split(" ms")[0])
            sdk_cpu, sdk_wall, sdk_failed = robotis_sdk_cycle(link, list(range(1, args.ids + 1)), args.cycles)
            print(f"robotis dynamixel_sdk sync_read+sync_write: cpu {sdk_cpu:.4f} ms/cycle, wall {sdk_wall:.3f} ms/cycle, "
                  f"failed cycles {sdk_failed}")
            print(f"cpu per cycle, SDK / ours (sync read): {sdk_cpu / cpp_cpu:.1f}x (target: >= 10x)")
        finally:
            mock.send_signal(signal.SIGTERM)
            mock.wait(10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
