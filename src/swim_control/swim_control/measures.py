"""The paper's tracking measure (Sec. 7): the two-norm of an error signal, ||e||_2 = sqrt(int e(t)^2 dt).

One rule for every caller (the in-process closed loop here, swim_bringup's analysis of recorded runs): the
trapezoidal rule over the samples, so a measure does not depend on who computed it.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt


def two_norm(time_s: npt.ArrayLike, error: npt.ArrayLike) -> float:
    """The paper's tracking measure ||e||_2 = sqrt(int e(t)^2 dt), by the trapezoidal rule.

    Parameters
    ----------
    time_s : (n,) array_like
        The sample times, s, increasing.
    error : (n,) array_like
        The error signal at those times, in any unit.

    Returns
    -------
    float
        ||e||_2, in the error's unit times s^0.5; 0 for fewer than two samples (no interval).

    Raises
    ------
    ValueError
        If the two are not one-dimensional arrays of the same length.

    References
    ----------
    Saimek & Li 2004, Sec. 7.
    """
    times, values = np.asarray(time_s, dtype=float), np.asarray(error, dtype=float)
    if times.ndim != 1 or times.shape != values.shape:
        raise ValueError(f"two_norm takes times and errors of one shape (n,); got {times.shape} and {values.shape}")
    return float(np.sqrt(np.trapezoid(values ** 2, times)))
