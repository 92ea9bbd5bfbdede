"""Checks used by the tests only (the open-loop replay of a primitive through the model).

Nothing a user runs imports them.
"""
