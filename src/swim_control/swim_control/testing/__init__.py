"""Fixtures for the tests of swim_control and of the packages above it (the rig, its models, smooth strokes with
their gains, one-segment trajectories): nothing a user runs imports it.
"""
