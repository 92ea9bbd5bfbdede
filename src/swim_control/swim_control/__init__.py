"""The trajectory core under the planner and the tracker: the one trajectory type, time scaling (Theorem 1), the
LQ stage's Riccati gains, the paper's tracking measure and the plan errors. Pure Python on swim_model, no ROS."""
