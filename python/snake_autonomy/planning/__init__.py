"""Motion planners (ROS-free): rectilinear/ is perception-space navigation with the rectilinear gait
(Chang et al.); fbsr/ is the FBSR head-raising "scout" planner (Cappel & Choset)."""
