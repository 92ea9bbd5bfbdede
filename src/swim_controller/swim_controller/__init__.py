"""The cascade tracker: time-varying LQR with time-scaled gains, input-output linearization and
sliding mode.
"""
