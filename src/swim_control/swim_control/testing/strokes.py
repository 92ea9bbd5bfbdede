"""Pytest fixtures of smooth strokes to linearize about, made here rather than planned.

The LQ stage and Theorem 1 hold about any trajectory, so these tests need no planner. The fixtures: the rig, its vehicle
models, the strokes with P and G'P, and one-segment trajectories. A package's conftest imports the fixtures it uses by
name.
"""
import dataclasses
import math

import numpy as np
import pytest

from swim_control.riccati import LqrWeights, TrackingGains, error_state_size, primitive_gains
from swim_control.trajectory import Segment, Trajectory
from swim_model import VehicleModel, load_rig


@pytest.fixture(scope="session")
def rig():
    """The rig description (swim_model.load_rig's default)."""
    return load_rig()


@dataclasses.dataclass(frozen=True)
class StrokeSpec:
    """Which stroke to make: the primitive it stands in for, its vehicle, lane radius (m) and intervals per cycle."""

    primitive_id: str
    constrained: bool
    lane_radius_m: float
    intervals: int           # per cycle; samples at knots and midpoints, as a primitive's


@dataclasses.dataclass(frozen=True)
class Stroke:
    """What the tests read of a primitive: samples of q, qdot, u = psi_ddot, and P, G'P for the default weights."""

    spec: StrokeSpec
    time_s: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    foil_acceleration: np.ndarray
    gains: TrackingGains


def make_stroke(model: VehicleModel, spec: StrokeSpec, period_s: float = 1.0, cycles: int = 2,
                cycle_samples: bool = False) -> Stroke:
    """Heave 0.1 + 0.3 sin(w t), pitch 0.4 cos(w t) (rad), alpha advancing 0.05 rad/s, R 1 cm about the lane.

    A smooth periodic stroke of the rig's size, with exact derivatives.
    """
    samples_per_cycle = 2 * spec.intervals
    time_s = np.linspace(0.0, cycles * period_s, cycles * samples_per_cycle + 1)
    w = 2.0 * math.pi / period_s
    s, c = np.sin(w * time_s), np.cos(w * time_s)
    columns = [(0.05 * time_s, np.full_like(time_s, 0.05), np.zeros_like(time_s))]
    if not spec.constrained:
        columns.append((spec.lane_radius_m + 0.01 * s, 0.01 * w * c, -0.01 * w * w * s))
    columns += [(0.1 + 0.3 * s, 0.3 * w * c, -0.3 * w * w * s), (0.4 * c, -0.4 * w * s, -0.4 * w * w * c)]
    q, qdot, qddot = (np.stack([col[i] for col in columns], axis=1) for i in range(3))
    foil_acceleration = qddot[:, -2:]
    gains = primitive_gains(model, time_s, q, qdot, foil_acceleration, LqrWeights(),
                            samples_per_cycle + 1 if cycle_samples else None)
    return Stroke(spec, time_s, q, qdot, foil_acceleration, gains)


@pytest.fixture(scope="session")
def model_for(rig):
    """VehicleModel for a spec, built once per (constrained, lane)."""
    cache = {}

    def make(spec) -> VehicleModel:
        key = (spec.constrained, spec.lane_radius_m)
        if key not in cache:
            cache[key] = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m)
        return cache[key]
    return make


@pytest.fixture(scope="session")
def strokes(model_for):
    """{"constrained" | "free": Stroke} (two 1 s cycles, 40 intervals each), with P and G'P."""
    specs = [StrokeSpec("constrained", True, 0.43, 40), StrokeSpec("free", False, 0.43, 40)]
    return {spec.primitive_id: make_stroke(model_for(spec), spec) for spec in specs}


def one_segment_trajectory(time_s, q, qdot, foil_acceleration=None, torque=None, gain=0.0, lqr_gain=None,
                           riccati_input_gain=None, time_scale=1.0) -> Trajectory:
    """A Trajectory of the samples given as one segment at time_scale.

    The inputs u and tau are zero unless given, every gain entry equal to gain unless the gains are given.
    """
    samples, nq = np.shape(q)
    n = error_state_size(nq, nq - 2)
    zero = np.zeros((samples, 2))
    segment = Segment("test/segment", "cruise", 0, 0.0, float(time_s[-1]), time_scale, 0.0, 0, samples)
    return Trajectory(time_s, q, qdot, zero if foil_acceleration is None else foil_acceleration,
                      zero if torque is None else torque,
                      np.full((samples, 2, n), gain) if lqr_gain is None else lqr_gain,
                      np.full((samples, 2, n), gain) if riccati_input_gain is None else riccati_input_gain,
                      (segment,), lane_radius_m=0.43)


@pytest.fixture(scope="session")
def make_trajectory():
    """one_segment_trajectory, for the tests (a conftest is not imported by name)."""
    return one_segment_trajectory
