"""snake_autonomy.runs: runs of the robot's own loops on the simulator, and their records.

Harnesses (each drives the mission runner, the planner or the C++ driver on sim/'s plant):
batch.py (one mission: the lock-step driver, feedback, runner, evaluation), mission_experiment.py
(missions x seeds in processes), nav_batch.py + nav_experiment.py (the navigation loop in a world;
random corridors x seeds), gait_driver.py (a gait through the C++ driver on the plant), gait_map.py
and turn_sweep.py (gait and steering sweeps), sweep_runner.py (Dask / threads / serial), render_set.py
(labelled camera renders for perception), scout_executor.py + scout_execute.py (FBSR trajectories
through the driver; a plan in physics).

Records (also written by the mission node on the robot): results.py (metrics and the results
folder from plain arrays, no ROS), plots.py, run_log.py (the run's bag and live metrics: rosbag),
bag_io.py (a bag back to arrays and to the results folder), recorded_topics.py (what a run records).
"""
