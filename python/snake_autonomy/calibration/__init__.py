"""snake_autonomy.calibration: the tracker's steering calibration (thesis 3.6.4, eq. 3.31) and heading
offset, measured on the simulated robot (sim_backend) or on the robot through ROS (ros_backend) by one
sequence (sequence.run_plan) and one analysis (analysis.fit); `snake_autonomy calibrate`
(cli/calibrate.py)."""
