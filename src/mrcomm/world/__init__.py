"""World layer: maps (ROS map_server format), occupancy grids, inflation, line of sight,
scenario and task files."""
