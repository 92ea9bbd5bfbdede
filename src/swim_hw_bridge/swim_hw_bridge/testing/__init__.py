"""Stand-ins for the rig's hardware, for tests only: the serial firmware on a pseudo-terminal and the MF624's
Comedi and counter registers. Nothing a user runs imports them.
"""
