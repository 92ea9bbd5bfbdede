"""The rig in RViz and Foxglove: its URDF, its frames from joint_states, and markers of the paths."""
