"""Tracking gains for a library's primitives (swim_control.riccati), and LQ weights from YAML.

The gains P(t), G'P of every primitive are computed once, off-line, for the library's LQ weights and stored
with it. To compare tunings (paper Sec. 7) without rebuilding, ``RetunedLibrary`` shows the same library with
gains for other weights, each primitive's computed on first use (0.1-0.3 s, a backward Riccati solve) and
kept; the control loop itself never solves a Riccati equation.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import threading
from pathlib import Path
from typing import Optional

import numpy as np
import yaml

from swim_control.errors import GainComputationError
from swim_control.riccati import LqrWeights, primitive_gains
from swim_model import RigParameters, VehicleModel
from swim_planner.errors import PlannerError, PrimitiveSolveError
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitives import Primitive, PrimitiveSpec, PrimitiveType


def gains_job(rig: RigParameters, primitive: Primitive, lqr_weights: LqrWeights) -> Primitive:
    """The primitive with its LQ gains P(t), G'P computed (swim_control.riccati), once, off-line.

    A primitive with lag states was solved with the circulatory flow model: its gains are for that model, on the
    extended error state (int e_y, e_q, edot_q, e_z).
    """
    spec = primitive.spec
    flow = "ideal" if primitive.lag is None else "circulatory"
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m, flow=flow)
    try:
        cycle_samples = 2 * spec.intervals + 1 if spec.primitive_type is PrimitiveType.CRUISE else None
        gains = primitive_gains(model, primitive.time_s, primitive.q, primitive.qdot, primitive.foil_acceleration,
                                lqr_weights, cycle_samples, primitive.lag,
                                ends_at_rest=spec.primitive_type is PrimitiveType.DECELERATE)
    except GainComputationError as err:
        raise PrimitiveSolveError(f"{spec.primitive_id}: {err}") from err
    return dataclasses.replace(primitive, gains=gains)


def load_lqr_weights(path: str | Path, base: LqrWeights = LqrWeights()) -> LqrWeights:
    """LqrWeights from a YAML mapping of its field names.

    The fields it does not name are those of base (a library's own weights, or the package defaults).
    """
    names = {field.name for field in dataclasses.fields(LqrWeights)}
    try:
        values = yaml.safe_load(Path(path).read_text()) or {}
        unknown = sorted(set(values) - names)
        if unknown:
            raise ValueError(f"unknown fields {unknown}; known: {sorted(names)}")
        weights = dataclasses.replace(base, **{key: float(value) for key, value in values.items()})
        weights.validate()
    except (OSError, yaml.YAMLError, TypeError, ValueError, AttributeError) as err:
        raise PlannerError(f"{path}: not a valid LQR weights file: {err}") from err
    return weights


class RetunedLibrary:
    """A read-only view of a PrimitiveLibrary whose primitives carry gains for other LQ weights.

    It answers what ``maneuver.concatenate`` and the graph ask of a library (ids, spec, get, digest,
    lqr_weights, path); the digest names the weights too, so a plan says which tuning its gains are for.
    Thread-safe: each primitive's gains are computed once, and computing one blocks only those asking for it.
    """

    def __init__(self, library: PrimitiveLibrary, lqr_weights: LqrWeights) -> None:
        lqr_weights.validate()
        self.library, self.lqr_weights = library, lqr_weights
        self.path = library.path
        self._retuned: dict[str, Primitive] = {}
        self._locks: dict[str, threading.Lock] = {}
        self._locks_lock = threading.Lock()

    def ids(self) -> list[str]:
        """The library's primitive ids."""
        return self.library.ids()

    def __contains__(self, primitive_id: str) -> bool:
        """Whether the library holds primitive_id."""
        return primitive_id in self.library

    def __len__(self) -> int:
        """The number of primitives in the library."""
        return len(self.library)

    def spec(self, primitive_id: str) -> PrimitiveSpec:
        """The spec of primitive_id, as the library stores it."""
        return self.library.spec(primitive_id)

    def sample_count(self, primitive_id: str) -> int:
        """The number of samples of primitive_id, as the library stores it."""
        return self.library.sample_count(primitive_id)

    def get(self, primitive_id: str) -> Primitive:
        """The primitive primitive_id with its gains for lqr_weights, computed on first use."""
        with self._locks_lock:
            lock = self._locks.setdefault(primitive_id, threading.Lock())
        with lock:
            if primitive_id not in self._retuned:
                self._retuned[primitive_id] = gains_job(self.library.rig, self.library.get(primitive_id),
                                                        self.lqr_weights)
            return self._retuned[primitive_id]

    def disturbance_bound(self, primitive_id: str) -> Optional[np.ndarray]:
        """The library's stored D(t) of a primitive (new weights change the gains, not the flow's force)."""
        return self.library.disturbance_bound(primitive_id)

    def digest(self) -> str:
        """SHA-256 of the library's digest and the weights."""
        weights = json.dumps(dataclasses.asdict(self.lqr_weights), sort_keys=True)
        return hashlib.sha256((self.library.digest() + weights).encode()).hexdigest()
