"""launch/sim.launch ended the two ways a user ends it, in a process group
of its own on a master port of its own:
- Ctrl+C: SIGINT reaches every node at once; the driver's shutdown action (its final hold write)
  must reach the simulated servos before the sim node closes the mocked bus.
- SIGKILL of roslaunch alone: the nodes are left behind; the mission node notices it lost its
  launcher, ends its mission and exits, and the driver holds when its command lifetime expires."""
import os
import re
import shutil
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HOLD_OK = "[driver] shutdown: servos left in 'hold'"
HOLD_FAILED = "(the bus did not take the write)"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _package_found() -> bool:
    try:
        import rospkg
        rospkg.RosPack().get_path("snake_autonomy")
        return True
    except Exception:  # noqa: BLE001 - no ROS environment: skip
        return False


needs_ros = pytest.mark.skipif(shutil.which("roslaunch") is None or not _package_found(),
                               reason="needs roslaunch and the built package (run through scripts/with-env)")


class Launch:
    """roslaunch snake_autonomy sim.launch ARGS in a new session; every output line collected."""

    def __init__(self, tmp_path, *args):
        self.tmp_path = tmp_path
        port = _free_port()
        env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(tmp_path),
                   ROS_LOG_DIR=str(tmp_path / "log"), PYTHONUNBUFFERED="1")
        cmd = ["roslaunch", "-p", str(port), "snake_autonomy", "sim.launch", f"port:={tmp_path}/bus",
               f"results_dir:={tmp_path}/results", *args]
        self.proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True)
        self.lines = []
        self._cond = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line)
                self._cond.notify_all()

    def wait_line(self, text, timeout_s, start=0):
        """Index of the first line from `start` on that contains `text`; AssertionError on timeout."""
        return self.wait_line_any((text,), timeout_s, start)

    def wait_line_any(self, texts, timeout_s, start=0):
        """Index of the first line from `start` on that contains one of `texts`."""
        def found():
            return next((i for i in range(start, len(self.lines)) if any(t in self.lines[i] for t in texts)), None)
        with self._cond:
            if not self._cond.wait_for(lambda: found() is not None, timeout_s):
                raise AssertionError(f"no line with any of {texts!r} within {timeout_s} s:\n" +
                                     "".join(self.lines[-40:]))
            return found()

    def close(self):
        """Kills whatever is left: roslaunch's process group, and the nodes it started, which roslaunch
        puts in sessions of their own (a SIGKILLed roslaunch leaves them running, with the master):
        every process whose command line names this test's folder (their __log:= argument)."""
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.proc.wait(timeout=30)
        self._reader.join(5)
        _kill_processes_naming(str(self.tmp_path))


def _kill_processes_naming(text: str) -> None:
    """SIGKILL every process (but this one) whose command line contains `text`."""
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmdline = f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if text in cmdline:
            try:
                os.kill(int(entry), signal.SIGKILL)
            except ProcessLookupError:
                pass


@needs_ros
def test_sigint_of_sim_launch_lets_the_driver_write_its_final_hold(tmp_path):
    launch = Launch(tmp_path, "auto_start:=false")
    try:
        # The driver's first snapshot (stderr, unbuffered): started, torque on, its loop running.
        launch.wait_line("driver: base pose", 180)
        os.killpg(launch.proc.pid, signal.SIGINT)   # as a terminal's Ctrl+C
        launch.proc.wait(timeout=60)
    finally:
        launch.close()
    final = [line for line in launch.lines if "[driver] shutdown:" in line]
    assert final, "the driver never reported its shutdown action:\n" + "".join(launch.lines[-60:])
    assert HOLD_OK in final[-1] and HOLD_FAILED not in final[-1], final[-1]


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as f:
            return not any(line.startswith("State:") and "Z" in line for line in f)
    except FileNotFoundError:
        return False


@needs_ros
def test_sigkill_of_roslaunch_stops_the_robot_through_the_command_lifetime(tmp_path):
    mission = ROOT / "test" / "ros" / "missions" / "sim_far.yaml"
    launch = Launch(tmp_path, f"mission:={mission}", "auto_start:=true")
    try:
        launch.wait_line("driver: base pose", 180)
        started = launch.wait_line("mission 'sim_far' started", 60)
        pid_line = launch.lines[launch.wait_line("process[mission-", 5)]
        mission_pid = int(re.search(r"pid \[(\d+)\]", pid_line).group(1))
        # Kill only once the mission's gait commands run the driver (the pose comes first; killed
        # before that, the driver never ran and has no command lifetime to expire) or it faulted.
        launch.wait_line_any(("driver: running", "driver: locomotion stopped"), 60, start=started)
        os.kill(launch.proc.pid, signal.SIGKILL)    # roslaunch alone: its nodes are left behind
        gone = launch.wait_line("is gone: ending the mission", 10, start=started)
        deadline = time.monotonic() + 15
        while _alive(mission_pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _alive(mission_pid), "the mission node is still running without its launcher"
        # The driver, left behind too, gets no more commands: it holds once its lifetime expires
        # (unless it never ran: on a heavily loaded machine the mocked bus can answer too late at
        # start and the driver faults, which holds as well).
        faulted = any("driver: locomotion stopped" in line for line in launch.lines[:gone])
        print(f"driver faulted at start (hold not checked): {faulted}")
        if not faulted:
            launch.wait_line("holding: no gait command", 10, start=gone)
    finally:
        launch.close()
