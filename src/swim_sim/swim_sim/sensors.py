"""What the rig's sensors make of the state: encoder quantization (paper Sec. 2) and measurement noise.

An incremental encoder with L lines per unit read with x4 quadrature decoding counts 4 L per unit, so a
position is known to 1 / (4 L): hub 2 pi / (4 x 6144) rad, rail 0.0254 / (4 x 1024) m, heave and pitch
2 pi / (4 x 512 x gear ratio) rad at the joint (the encoders sit on the motors, before the 43:1 and 25:1
gearheads). The measured position is floor((q + noise) 4 L) / (4 L) with Gaussian noise of a fraction of a count
(electrical noise and backlash, assumed); velocities are the model's plus Gaussian noise (a source with
tachometers or a filtered estimator), or are left out so that the controller differentiates positions itself.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt

from swim_model import VehicleModel

Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class SensorNoise:
    """Measurement model sizes; all assumed (the paper gives the resolutions only)."""

    quadrature_factor: float = 4.0          # assumed: x4 decoding, counts per line
    position_noise_counts: float = 0.3      # assumed: std of the position noise, in counts, before quantizing
    velocity_noise_fraction: float = 0.01   # assumed: velocity noise std per (count / sample period)
    quantize: bool = True

    def validate(self) -> None:
        """Raise ValueError for a negative or non-finite setting, or a zero quadrature_factor."""
        for name in ("quadrature_factor", "position_noise_counts", "velocity_noise_fraction"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0) or (name == "quadrature_factor" and value == 0.0):
                raise ValueError(f"sensor {name} must be finite and >= 0 (quadrature_factor > 0), got {value!r}")


def counts_per_unit(model: VehicleModel, quadrature_factor: float = 4.0) -> Array:
    """Counts per rad (or per m for R) of each of the model's coordinates (paper Sec. 2 resolutions)."""
    rig = model.rig
    per_unit = {
        "alpha": rig.hub_encoder_lines_per_rev / (2 * math.pi),
        "R": rig.rail_encoder_lines_per_m,
        "phi": rig.heave_encoder_lines_per_rev * rig.heave_gear_ratio / (2 * math.pi),
        "theta": rig.pitch_encoder_lines_per_rev * rig.pitch_gear_ratio / (2 * math.pi),
    }
    return quadrature_factor * np.array([per_unit[name] for name in model.joint_names])


class Sensors:
    """Quantized, noisy measurements of (q, qdot), drawn from a generator the caller seeds."""

    def __init__(self, model: VehicleModel, noise: SensorNoise = SensorNoise(), sample_period_s: float = 0.008):
        noise.validate()
        self.noise = noise
        self.counts_per_unit = counts_per_unit(model, noise.quadrature_factor)
        # one count per period as a velocity: the differencing quantum the noise is scaled by
        self.velocity_quantum = 1.0 / (self.counts_per_unit * sample_period_s)

    def measure(self, q: Array, qdot: Array, rng: np.random.Generator) -> tuple[Array, Array]:
        """(positions, velocities) as the encoders and the velocity source report them."""
        counts = q * self.counts_per_unit + self.noise.position_noise_counts * rng.standard_normal(q.shape)
        positions = (np.floor(counts) if self.noise.quantize else counts) / self.counts_per_unit
        velocities = qdot + self.noise.velocity_noise_fraction * self.velocity_quantum * rng.standard_normal(q.shape)
        return positions, velocities
