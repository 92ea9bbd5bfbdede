"""Stand-ins for the rig's hardware, for tests only; nothing a user runs imports them.

The serial firmware on a pseudo-terminal, and the MF624's Comedi and counter registers.
"""
