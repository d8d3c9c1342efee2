"""The FBSR head-raising planner (Cappel & Choset).

config.py     config/scout.yaml: planner parameters and each robot's lying posture, validated
chain.py      kinematics with the world fixed at the tail, the lying posture, ground contacts
batch_kinematics.py  the same FK with numpy on a batch of postures (the cost and its gradient)
support.py    support polygons, the ZMP's distance to their edges (shapely)
collision.py  self-collision: capsule-capsule clearance of non-adjacent modules
spline.py     the one-parameter cubic of eq. 3-8
cost.py       C = K1 Cd + K2 Cs + K3 Cp (+ torque, ground and clearance terms), eq. 9-15
stage.py      one optimised stage (scipy) with its global checks and random restarts
planner.py    the loop of section II / III.E, dynamic weighting of K1, lowering
plan_io.py    plan.json (the issue's contract), reading and validating it
figures.py    ZMP paths in the support polygons per stage (fig. 7), head height over time
pipe_scene.py the hanging pipe of fig. 6 as MJCF for the plant
trajectory.py a plan as the driver's JointTrajectory points, checked against its velocity limit
build.py      the planner for a robot name or YAML (model, config/scout.yaml, torque limit)

Running a plan in the MuJoCo plant: runs/scout_execute.py; the command line: cli/scout.py.
"""
