"""The closed loop brought up, run, recorded and analysed: the paper's experiments and the operator's commands."""
