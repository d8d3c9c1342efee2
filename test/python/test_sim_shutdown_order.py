"""Ctrl+C of launch/sim.launch (issue 10 point 8a): SIGINT reaches every node of the launch at once;
the driver's shutdown action (its final hold write) must reach the simulated servos before the sim
node closes the mocked bus. roslaunch runs in a process group of its own, on a master port of its
own, and the whole group gets SIGINT, as a terminal sends it."""
import os
import shutil
import signal
import socket
import subprocess
import threading
import time

import pytest

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


@pytest.mark.skipif(shutil.which("roslaunch") is None or not _package_found(),
                    reason="needs roslaunch and the built package (run through scripts/with-env)")
def test_sigint_of_sim_launch_lets_the_driver_write_its_final_hold(tmp_path):
    port = _free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(tmp_path),
               ROS_LOG_DIR=str(tmp_path / "log"), PYTHONUNBUFFERED="1")
    cmd = ["roslaunch", "-p", str(port), "snake_autonomy", "sim.launch", "auto_start:=false",
           f"port:={tmp_path}/bus", f"results_dir:={tmp_path}/results"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    lines, looping = [], threading.Event()

    def read():
        for line in proc.stdout:
            lines.append(line)
            # The driver's first snapshot (stderr, unbuffered): started, torque on, its loop running.
            if "driver: base pose" in line:
                looping.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert looping.wait(120), "the driver's loop never ran:\n" + "".join(lines[-40:])
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    reader.join(5)
    out = "".join(lines)
    final = [line for line in lines if "[driver] shutdown:" in line]
    assert final, "the driver never reported its shutdown action:\n" + out[-3000:]
    assert HOLD_OK in final[-1] and HOLD_FAILED not in final[-1], final[-1]
