"""Velocities from positions when the state source gives none: filtered backward differences.

qdot_k = a qdot_(k-1) + (1 - a) (q_k - q_(k-1)) / h_k,  a = exp(-2 pi f_c h_k): a first-order low-pass of
cutoff f_c on the difference quotient, as the paper's rig did with its encoder readings (Sec. 7).
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

DEFAULT_CUTOFF_HZ = 30.0   # assumed: above the 1-2 Hz strokes, below the 62.5 Hz Nyquist rate of 8 ms


class VelocityEstimator:
    """Filtered backward differences of positions: the velocity when the state source gives none.

    Parameters
    ----------
    cutoff_hz : float, optional
        f_c of the first-order low-pass, Hz.

    Raises
    ------
    ValueError
        For a cutoff that is not positive and finite.
    """

    def __init__(self, cutoff_hz: float = DEFAULT_CUTOFF_HZ) -> None:
        if not (math.isfinite(cutoff_hz) and cutoff_hz > 0.0):
            raise ValueError(f"cutoff must be positive and finite, got {cutoff_hz!r}")
        self.cutoff_hz = cutoff_hz
        self._last: Optional[tuple[float, Array]] = None
        self._rate: Optional[Array] = None

    def reset(self) -> None:
        """Forget the samples: the next update starts again from zero velocity."""
        self._last, self._rate = None, None

    def update(self, time_s: float, q: Array) -> Array:
        """The velocity estimate after a sample (zero until two samples are in).

        A sample not later than the last restarts the estimate.

        Parameters
        ----------
        time_s : float
            The sample's time, s.
        q : (n,) ndarray
            Positions, rad or m.

        Returns
        -------
        (n,) ndarray
            Velocity, rad/s or m/s.
        """
        if self._last is None or time_s <= self._last[0]:
            self._last, self._rate = (time_s, q.copy()), np.zeros_like(q)
            return self._rate.copy()
        assert self._rate is not None   # set with _last
        step = time_s - self._last[0]
        quotient = (q - self._last[1]) / step
        blend = math.exp(-2.0 * math.pi * self.cutoff_hz * step)
        self._rate = blend * self._rate + (1.0 - blend) * quotient
        self._last = (time_s, q.copy())
        return self._rate.copy()
