"""snake_autonomy.sim: the simulator, and nothing that drives it (that is runs/).

The plant (plant.py, mjcf.py, config.py: MuJoCo model and config/sim.yaml), its ventral scales
(scales.py), disturbances, the servos (servo_backend.py, servo_model.py, mujoco_servo_backend.py)
and the mock Dynamixel bus on a pty (mock_servo_bus.py, pty_serving.py), the sensors (mocap.py,
vio.py, camera.py, camera_process.py, collisions.py, feedback.py, odometry_gate.py and
vo_feedback.py: poses through the robot's own estimator), worlds (world_file.py, scene.py), the
simulated robot as a whole (world.py), wall-clock pacing (realtime.py), and gait patterns for
open-loop plant tests (cpg_gait.py, serpenoid.py, gait_metrics.py). MUJOCO_GL: see snake_autonomy/__init__.py.
"""
