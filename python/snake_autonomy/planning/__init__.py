"""Motion planners (ROS-free): fbsr/ is the FBSR head-raising "scout" planner (Cappel & Choset)."""
