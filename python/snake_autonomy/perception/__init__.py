"""snake_autonomy.perception: traversability from a head camera (ROS-free): ground / not ground."""
