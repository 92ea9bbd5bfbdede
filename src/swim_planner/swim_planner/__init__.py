"""Off-line optimal-control motion primitives, the primitive library, the lane/energy graph and the
maneuver planner node.
"""
