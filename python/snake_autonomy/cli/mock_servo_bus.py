"""Command line of the mocked servo bus (scripts/mock_servo_bus).

    scripts/mock_servo_bus --link /tmp/snake_bus --ids 1-11 [--baud 1000000] [--control PATH]

Creates the pty, a symlink at --link to it, and the control socket (default: LINK.ctl); prints
exactly one line ``ready LINK`` on stdout once it accepts packets; serves until SIGINT or SIGTERM,
then removes the symlink and the socket and exits 0. Faults at run time through the control
socket, e.g. from Python:

    from snake_autonomy.sim.mock_servo_bus import MockBusClient
    MockBusClient("/tmp/snake_bus.ctl").call("inject", kind="corrupt_crc", ids=[3], count=5)

or from a shell: echo '{"cmd": "stats"}' | socat - UNIX-CONNECT:/tmp/snake_bus.ctl
"""
import argparse
import signal
import sys

from snake_autonomy.sim.mock_servo_bus import DEFAULT_TABLE, MockServoBus, parse_ids
from snake_autonomy.sim.servo_model import KinematicServoBackend, KinematicServoParams


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mock_servo_bus", description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("--link", required=True, help="path of the symlink to the pty (the port clients open)")
    p.add_argument("--ids", default="1-11", help="servo IDs, e.g. 1-11 or 1,3,5-7 (default 1-11)")
    p.add_argument("--baud", type=int, default=1000000,
                   help="nominal baud rate (a pty ignores it; recorded for clients' timeouts)")
    p.add_argument("--control", help="control socket path (default LINK.ctl)")
    p.add_argument("--table", default=str(DEFAULT_TABLE), help="control table YAML")
    p.add_argument("--max-velocity", type=float, default=KinematicServoParams.max_velocity_rad_s,
                   help="servo speed limit, rad/s")
    p.add_argument("--time-constant", type=float, default=KinematicServoParams.time_constant_s,
                   help="servo tracking lag, s")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        ids = parse_ids(args.ids)
        if not 9600 <= args.baud <= 4500000:
            raise ValueError(f"--baud: {args.baud} is not in 9600..4500000")
        backend = KinematicServoBackend(ids, KinematicServoParams(max_velocity_rad_s=args.max_velocity,
                                                                  time_constant_s=args.time_constant))
        bus = MockServoBus(backend, ids, control_table=args.table)
    except ValueError as exc:
        print(f"mock_servo_bus: {exc}", file=sys.stderr)
        return 2
    control = args.control or f"{args.link}.ctl"
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: bus.request_stop())
    try:
        tty = bus.open_pty(args.link)
        bus.listen_control(control)
        print(f"mock_servo_bus: {len(ids)} servos {args.ids} on {tty} (link {args.link}), control socket "
              f"{control}", file=sys.stderr, flush=True)
        bus.serve_forever(on_ready=lambda: print(f"ready {args.link}", flush=True))
    finally:
        bus.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
