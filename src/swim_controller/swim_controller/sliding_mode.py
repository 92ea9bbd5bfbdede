"""The sliding-mode outer loop (paper Sec. 6.3, eqs. 24-25; docs/model_and_method.md section 5.3).

Derivation. Let the plant be Mm(q) qddot + Cm(q, qdot) qdot = [0; tau + d] with d an unknown torque
disturbance on the foil's motors (the matched part of what the ideal model leaves out), ||d|| <= D. With
tau = tau1 + eps and the I/O linearization tau1 = Mio u + Cio qdot (eqs. 22-23), eliminating yddot from
eq. 14 gives psiddot = u + Mio^-1 (eps + d), and Mm^-1 [0; I] = B Mio^-1 with B = [-Mm11^-1 Mm12; I] = df/du.
So the error system is xdot = F x + G (du + Mio^-1 (eps + d)) with du = -R^-1 G'P x the LQ feedback.
Along it, V = x' P x (P from eq. 20) has

    Vdot = -x'Qx - x'PGR^-1G'Px + 2 (G'Px)' Mio^-1 (eps + d) = -x'Qx - ||R^-1/2 G'Px||^2 + 2 s'(eps + d)

with s = Mio^-1 G'P x (Mio is symmetric). Choosing eps = -D s / ||s|| makes 2 s'(eps + d) <= 2 ||s|| (||d|| - D)
<= 0, so V decreases at least as fast as without the disturbance (eq. 25). (The extracted text of the
paper writes s with an extra K'; with the matched input map above no K is needed.) To keep eps from
chattering, the unit vector s / ||s|| is replaced by s / phi inside a boundary layer ||s|| < phi, where eps
is linear in s and the guarantee weakens to ultimate boundedness of s. With time scaling, P and G are
those of the scaled system: G_l' P_l = (G'P)(lambda t) Gamma (see time_scaling).

D may vary with time: the argument above holds at each instant with ||d(t)|| <= D(t). A plan made with the
circulatory flow model may carry D(t), measured off-line from the difference between the planned flow's force and
the vortex wake's along each primitive (swim_planner.disturbance; time-scaled as a torque, lambda^2 D(lambda t));
the tracker then uses D = disturbance_bound_margin D_plan(t) (``term(s, bound)``), and without one the constant
``disturbance_bound_n_m``.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class SlidingMode:
    """The sliding-mode term eps = -D s / max(||s||, phi) with its boundary layer (eqs. 24-25).

    Attributes
    ----------
    disturbance_bound_n_m : float
        D, N m, >= 0: the constant bound on the matched torque disturbance, used where the plan carries none.
        Assumed: about 5 % of the pitch motor's limit (0.52 N m).
    boundary_layer : float
        phi > 0, in the units of s = Mio^-1 G'P x: inside ||s|| < phi the term is linear in s.
    disturbance_bound_margin : float
        >= 1: the factor on a plan's own D(t). Assumed: the plan's D(t) is the mismatch along the planned motion
        with the planned wake history, and the tracked vehicle moves a little off it.

    References
    ----------
    Saimek & Li 2004, Sec. 6.3, eqs. 24-25; docs/model_and_method.md section 5.3.
    """

    disturbance_bound_n_m: float = 0.02   # assumed: D, about 5 % of the pitch motor's limit (0.52 N m)
    boundary_layer: float = 1.0           # assumed: phi, in the units of s = Mio^-1 G'P x
    disturbance_bound_margin: float = 1.5
    # assumed: the plan's D(t) is the mismatch along the planned motion with the planned wake history; the tracked
    # vehicle moves a little off it and its wake's history differs (a start from rest, a re-planned maneuver), so
    # the bound used is 50 % above the measured one

    def validate(self) -> None:
        """Check the settings.

        Raises
        ------
        ValueError
            If D is negative or not finite, phi is not positive and finite, or the margin is below 1.
        """
        if not (math.isfinite(self.disturbance_bound_n_m) and self.disturbance_bound_n_m >= 0.0):
            raise ValueError(f"disturbance bound must be finite and >= 0, got {self.disturbance_bound_n_m!r}")
        if not (math.isfinite(self.boundary_layer) and self.boundary_layer > 0.0):
            raise ValueError(f"boundary layer must be finite and > 0, got {self.boundary_layer!r}")
        if not (math.isfinite(self.disturbance_bound_margin) and self.disturbance_bound_margin >= 1.0):
            raise ValueError(f"disturbance bound margin must be finite and >= 1, got {self.disturbance_bound_margin!r}")

    def term(self, sliding_variable: Array, plan_bound_n_m: Optional[float] = None) -> Array:
        """The sliding-mode torque eps for the sliding variable s.

        Parameters
        ----------
        sliding_variable : (2,) array
            s = Mio^-1 G_l' P_l x (eq. 24), heave and pitch.
        plan_bound_n_m : float, optional
            The plan's D(t) at this instant, N m; D is then ``disturbance_bound_margin`` times it. None: the plan
            has none, and D is the constant ``disturbance_bound_n_m``.

        Returns
        -------
        (2,) array
            eps = -D s / max(||s||, phi), N m (heave, pitch).
        """
        return sliding_variable * self.term_factor(math.hypot(sliding_variable[0], sliding_variable[1]),
                                                   plan_bound_n_m)

    def term_factor(self, sliding_norm: float, plan_bound_n_m: Optional[float] = None) -> float:
        """The factor -D / max(||s||, phi) with which eps = factor s.

        Parameters
        ----------
        sliding_norm : float
            ||s||, in the units of s.
        plan_bound_n_m : float, optional
            The plan's D(t) at this instant, N m, or None (D as in ``term``).

        Returns
        -------
        float
            -D / max(||s||, phi), N m per unit of s.
        """
        bound = self.disturbance_bound_n_m if plan_bound_n_m is None else \
            self.disturbance_bound_margin * plan_bound_n_m
        return -bound / max(sliding_norm, self.boundary_layer)
