"""snake_autonomy.missions: mission files (load + validate, ROS-free) and the mission runner."""
from .mission import (DEFAULT_GAIT_LIBRARY, MISSIONS_DIR, Mission, MissionError, gait_library_names,
                      load_defaults, load_mission, validate_mission)

__all__ = ["Mission", "MissionError", "load_mission", "validate_mission", "load_defaults",
           "gait_library_names", "DEFAULT_GAIT_LIBRARY", "MISSIONS_DIR"]
