"""snake_autonomy.sim (MUJOCO_GL: see snake_autonomy/__init__.py)"""
