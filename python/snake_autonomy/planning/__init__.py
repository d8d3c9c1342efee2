"""snake_autonomy.planning: planners (rectilinear perception-space navigation, issue 13)."""
