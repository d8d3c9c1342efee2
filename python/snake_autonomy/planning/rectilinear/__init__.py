"""Navigation with the rectilinear gait reduced to a unicycle (Chang et al.): perception-space
collision checks, arc sampling, receding-horizon following, the gait's Python reference."""
