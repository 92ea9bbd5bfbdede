"""The closed loop in one process (the tracker driving a model or a plant, no ROS), for tests and benchmarks only.

Nothing a user runs imports it.
"""
