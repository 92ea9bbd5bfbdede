"""Fixtures for the tests of swim_control and of the packages above it.

The rig, its models, smooth strokes with their gains, one-segment trajectories. Nothing a user runs imports it.
"""
