"""Motion primitives, what they are (paper Secs. 4-5; docs/model_and_method.md section 3).

Their types, specs and planning limits, a solved primitive's samples and gains, and the solver settings it was
made with.

Plain data, no optimizer: the library, the graph and planner_node read primitives through this module;
swim_planner.primitive_solver solves them (the optimal-control problem of each type is described there).
"""
from __future__ import annotations

import dataclasses
import enum
import math
from typing import Optional

import numpy as np
import numpy.typing as npt

from swim_control.riccati import TrackingGains
from swim_model import RigParameters, VehicleModel

Array = npt.NDArray[np.float64]


class PrimitiveType(str, enum.Enum):
    """The five primitive types of the paper (Secs. 4-5; docs/model_and_method.md section 3)."""

    ACCELERATE = "accelerate"
    CRUISE = "cruise"
    DECELERATE = "decelerate"
    CRUISE_TO_CRUISE = "cruise_to_cruise"
    LANE_CHANGE = "lane_change"


@dataclasses.dataclass(frozen=True)
class PlanningLimits:
    """Limits every primitive respects: the joint ranges are the rig's planning ranges (PlanningLimits.of).

    The paper gives none of these; the others are assumed values, each with its reason in the comment at its field.

    Attributes
    ----------
    heave_range_rad : float
        |phi| bound, rad.
    pitch_range_rad : float
        |theta| bound, rad.
    torque_fraction : float
        The share of the motor limits a plan may use, in (0, 1].
    foil_acceleration_limit_rad_s2 : float
        |u| bound, rad/s^2.
    lane_band_m : float
        Rb, the lateral band around the lanes, m.
    min_alpha_rate_rad_s : float
        v_min of eq. 12, rad/s.
    angle_of_attack_limit_rad : float
        |angle of attack| bound of the foil frame (eq. 40), rad, circulatory flow only.
    angle_of_attack_free_from_rest_s : float
        The window next to rest where the angle-of-attack bound is left out, s, circulatory flow only.
    """

    heave_range_rad: float                         # |phi| <= this: the rig's heave_planning_range
    pitch_range_rad: float                         # |theta| <= this: the rig's pitch_planning_range
    torque_fraction: float = 0.35                  # assumed: plan with 35 % of the motor limits, so that the
                                                   # paper's fastest scaling, lambda = 1.67 (Sec. 7.1), fits:
                                                   # 0.35 * 1.67^2 = 0.98
    foil_acceleration_limit_rad_s2: float = 300.0  # assumed: bounds u to keep the NLP well scaled
    lane_band_m: float = 0.03                      # assumed: Rb, the lateral band around the lanes
    min_alpha_rate_rad_s: float = 0.0              # v_min of eq. 12 (assumed: never swim backwards)
    angle_of_attack_limit_rad: float = math.radians(20.0)
    # assumed, circulatory flow only: |angle of attack| of the foil frame (swim_model.flow.angle_of_attack, eq. 40)
    # at the collocation points outside angle_of_attack_free_from_rest_s. A NACA 0012-like section stalls
    # statically near 12-15 deg; oscillating, its lift peaks later, at 20-25 deg (McCroskey, AGARD-CP-227,
    # 1981). 20 deg keeps the plans at the attached end
    # of swim_model.flow's stall transition (stall_angle_rad 25 deg, width 2.5 deg: attached weight 0.997 at
    # 20 deg), where the reduced model is the validated thin-aerofoil theory and not its flat-plate fallback
    angle_of_attack_free_from_rest_s: float = 0.2
    # assumed, circulatory flow only: the angle-of-attack bound is left out within this time of rest (an
    # accelerate's start, a decelerate's end). From rest no foil motion starts inside the bound: with p_alpha
    # still about 0 the hub barely turns, and a slow foil motion inside 20 deg exists only with the foil pitched
    # more than about 50-60 deg off its heave link (measured over the heave and pitch ranges with p_alpha = 0).
    # Pitching it there is a turn about the pitch axis, broadside to its own motion: about 60 deg takes at least
    # 2 sqrt(1.05 rad / 300 rad/s^2) = 0.12 s at foil_acceleration_limit_rad_s2. With 0.15 s the constrained
    # E = 0.05 accelerate is infeasible, with 0.2 s it solves. The window holds 7 of the 161 samples of a 4 s
    # accelerate or decelerate (4.3 %) and 17 of the 401 of a free 5 s decelerate (4.2 %); the angle is unbounded
    # only there. A speed floor at every time, U tan(a) + c >= |V| with c = 1 cm/s, instead lets the accelerate
    # crawl at any angle for its first second (95th percentile 73 deg over its samples)

    @classmethod
    def of(cls, rig: RigParameters, **others: float) -> "PlanningLimits":
        """The limits for rig.

        Its joints' planning ranges (its limits record), the other fields as others give them or their defaults.
        """
        return cls(heave_range_rad=rig.limits.heave.planning_range_rad,
                   pitch_range_rad=rig.limits.pitch.planning_range_rad, **others)

@dataclasses.dataclass(frozen=True)
class PrimitiveSpec:
    """What one primitive is. ``start_from``/``end_at`` name the primitives whose states it joins.

    The comment at a field gives its reason where it has one.

    Attributes
    ----------
    primitive_id : str
        The library's id, e.g. "constrained/cruise/E0.05".
    primitive_type : PrimitiveType
        Its type.
    constrained : bool
        The laterally constrained vehicle, else the free one.
    duration_s : float
        Tf, s (a cruise: all its cycles).
    lane_radius_m : float
        R of the lane it starts on, m.
    end_lane_radius_m : float
        R of the lane it ends on, m.
    energy_j : float or None
        A cruise's level E, J (the cycle's mean kinetic energy).
    start_from : str or None
        Id of the primitive whose end state is its start.
    end_at : str or None
        Id of the primitive whose start state is its end.
    speeding_up : bool
        Cruise-to-cruise: the sign of alpha(Tf) in the index (eq. 13).
    intervals : int
        Collocation intervals (per cycle for a cruise).
    cycles : int
        A cruise's cycle is solved once and repeated this often.
    heave_effort_weight : float
        w_h of eq. 10 (assumed), rad/(N^2 m^2 s).
    pitch_effort_weight : float
        w_p of eq. 10 (assumed), rad/(N^2 m^2 s).
    input_smoothness_weight : float
        w_u (assumed), rad/(rad/s^3)^2/s, on the rate of u.
    end_lag_free : bool
        Circulatory flow, a decelerate: its lag states at rest are left free (else still water).
    angle_of_attack_continuation_rad : tuple of float
        Circulatory flow: looser angle-of-attack bounds, rad, descending, solved in turn before the limit
        (``primitive_solver.solve_primitive``); empty: one solve.
    coarse_intervals : int or None
        Intervals of a coarser grid solved first, below ``intervals``; None: none.
    min_strouhal : float or None
        Circulatory flow, a cruise: the least Strouhal number of its stroke; None: none.
    rest_window_s : float or None
        Circulatory flow, an accelerate or a decelerate: the window next to rest without the angle-of-attack
        bound, s; None: ``PlanningLimits.angle_of_attack_free_from_rest_s``.
    rest_window_foil_rate_limit_rad_s : float or None
        Circulatory flow, an accelerate or a decelerate: |heave rate| and |pitch rate| bound in that window, rad/s;
        None: none.

    Raises
    ------
    ValueError
        If coarse_intervals, the rest window, its rate limit or min_strouhal do not fit the type or are out of range.

    References
    ----------
    Saimek & Li 2004, Secs. 4-5, eqs. 9-13; docs/model_and_method.md section 3; docs/circulatory_primitives.md,
    "The problem".
    """

    primitive_id: str
    primitive_type: PrimitiveType
    constrained: bool
    duration_s: float
    lane_radius_m: float
    end_lane_radius_m: float
    energy_j: Optional[float] = None          # cruise: its level E
    start_from: Optional[str] = None          # id of the primitive whose end state is our start
    end_at: Optional[str] = None              # id of the primitive whose start state is our end
    speeding_up: bool = True                  # cruise-to-cruise: sign of alpha(Tf) in the index (eq. 13)
    intervals: int = 60                       # collocation intervals (per cycle for a cruise)
    cycles: int = 1                           # cruise: the cycle is solved once and repeated this often
    heave_effort_weight: float = 0.1          # w_h of eq. 10 (assumed), rad/(N^2 m^2 s)
    pitch_effort_weight: float = 0.1          # w_p of eq. 10 (assumed)
    input_smoothness_weight: float = 1e-8     # w_u (assumed), rad/(rad/s^3)^2/s: see solve_primitive
    end_lag_free: bool = False
    # circulatory flow, a decelerate: its lag states at rest (its end) are left free, the wake its braking leaves
    # (docs/circulatory_primitives.md, "The problem"); False: still water, rest_boundary_state
    angle_of_attack_continuation_rad: tuple[float, ...] = ()
    # circulatory flow: the looser angle-of-attack bounds, descending, solved in turn before
    # PlanningLimits.angle_of_attack_limit_rad, after a first solve without the bound, each from the last converged
    # solution (primitive_solver.solve_primitive); empty: one solve with the bound
    coarse_intervals: Optional[int] = None
    # collocation intervals of a coarser grid the primitive (its continuation included) is solved on first; its
    # solution, interpolated, starts the solve on ``intervals`` (primitive_solver.solve_primitive); None: none

    min_strouhal: Optional[float] = None
    # circulatory flow, a cruise: the least Strouhal number of its stroke (cruise_strouhal_number), asked of the
    # pitch axis's excursion across the lane from the cycle's start to its middle (primitive_solver); None: none

    rest_window_s: Optional[float] = None
    # circulatory flow, an accelerate or a decelerate: the window next to rest where the angle-of-attack bound is off
    # (primitive_solver.rest_window_s); None: PlanningLimits.angle_of_attack_free_from_rest_s
    rest_window_foil_rate_limit_rad_s: Optional[float] = None
    # circulatory flow, an accelerate or a decelerate: |heave rate| and |pitch rate| at most this within that
    # window (docs/circulatory_primitives.md, "The problem"); None: no bound but the foil accelerations'

    def __post_init__(self) -> None:
        """Check the fields that depend on the type (Raises, above)."""
        # a library's manifest stores the continuation as a JSON list: the spec read back equals the one written
        object.__setattr__(self, "angle_of_attack_continuation_rad",
                           tuple(float(a) for a in self.angle_of_attack_continuation_rad))
        if self.coarse_intervals is not None and not 0 < self.coarse_intervals < self.intervals:
            raise ValueError(f"{self.primitive_id}: coarse_intervals must be positive and below intervals "
                             f"({self.intervals}), got {self.coarse_intervals}")
        if self.coarse_intervals is not None and self.cycles > 1:
            raise ValueError(f"{self.primitive_id}: a coarser grid is for a primitive solved whole, not a cruise's "
                             f"repeated cycle (cycles {self.cycles})")
        for name in ("rest_window_s", "rest_window_foil_rate_limit_rad_s"):
            value = getattr(self, name)
            if value is not None and not (self.primitive_type in (PrimitiveType.ACCELERATE, PrimitiveType.DECELERATE)
                                          and isinstance(value, (int, float)) and not isinstance(value, bool)
                                          and math.isfinite(value) and value > 0.0):
                raise ValueError(f"{self.primitive_id}: {name} is an accelerate's or a decelerate's, finite and "
                                 f"positive; got {value!r} for a {self.primitive_type.value}")
        if self.min_strouhal is not None and not (self.primitive_type is PrimitiveType.CRUISE
                                                  and math.isfinite(self.min_strouhal) and self.min_strouhal > 0.0):
            raise ValueError(f"{self.primitive_id}: min_strouhal is a cruise's, finite and positive; got "
                             f"{self.min_strouhal!r} for a {self.primitive_type.value}")

    @property
    def solved_duration_s(self) -> float:
        """The horizon the optimizer sees: one cycle of a cruise, else the whole primitive."""
        return self.duration_s / self.cycles

    def index_sign(self) -> float:
        """The sign s of alpha(Tf) in the index J = s alpha(Tf) - effort (eqs. 10, 12, 13).

        Returns
        -------
        float
            -1 for a decelerate and a cruise-to-cruise or lane change that slows down, else +1.
        """
        if self.primitive_type is PrimitiveType.DECELERATE:
            return -1.0
        if self.primitive_type in (PrimitiveType.CRUISE_TO_CRUISE, PrimitiveType.LANE_CHANGE):
            return 1.0 if self.speeding_up else -1.0
        return 1.0


@dataclasses.dataclass
class Primitive:
    """A solved primitive on the fine grid (knots and midpoints of the collocation: N = 2 * intervals + 1 samples).

    Attributes
    ----------
    spec : PrimitiveSpec
        What it is.
    time_s : (N,) array
        Sample times from 0, s.
    q : (N, nq) array
        Positions, rad and m.
    qdot : (N, nq) array
        Velocities, rad/s and m/s.
    foil_acceleration : (N, 2) array
        u = psiddot, rad/s^2.
    torque : (N, 2) array
        (tau_h, tau_p), N m.
    index_j : float
        J = s alpha(Tf) - effort.
    effort : float
        int (w_h tau_h^2 + w_p tau_p^2) dt.
    solver_status : str
        IPOPT's return status.
    solve_time_s : float
        IPOPT's wall time, s.
    iterations : int
        IPOPT's iterations.
    gains : TrackingGains or None
        P(t) and G'P for the tracker.
    lag : (N, 2) array or None
        The flow's lag states z, m/s: circulatory flow only.
    """

    spec: PrimitiveSpec
    time_s: Array
    q: Array
    qdot: Array
    foil_acceleration: Array   # u = psiddot, rad/s^2
    torque: Array              # (tau_h, tau_p), N m
    index_j: float             # s alpha(Tf) - effort
    effort: float              # int (w_h tau_h^2 + w_p tau_p^2) dt
    solver_status: str
    solve_time_s: float
    iterations: int
    gains: Optional[TrackingGains] = None   # P(t) and G'P for the tracker (swim_control.riccati)
    lag: Optional[Array] = None             # the flow's lag states z, m/s, (samples, 2): circulatory flow only

    @property
    def start_state(self) -> tuple[Array, Array]:
        """(q, qdot) at the first sample, copies."""
        return self.q[0].copy(), self.qdot[0].copy()

    @property
    def end_state(self) -> tuple[Array, Array]:
        """(q, qdot) at the last sample, copies."""
        return self.q[-1].copy(), self.qdot[-1].copy()

    @property
    def start_boundary_state(self) -> tuple[Array, ...]:
        """The state a primitive joining this one's start must reach.

        (q, qdot), or (q, qdot, lag) with the circulatory flow.
        """
        return self.start_state + (() if self.lag is None else (self.lag[0].copy(),))

    @property
    def end_boundary_state(self) -> tuple[Array, ...]:
        """The state a primitive joining this one's end starts from: (q, qdot), or (q, qdot, lag)."""
        return self.end_state + (() if self.lag is None else (self.lag[-1].copy(),))


#: IPOPT statuses that count as converged: its full tolerance, or its "acceptable" one (acceptable_tol,
#: 1e-6); the library tests check every boundary condition and limit independently either way
CONVERGED_STATUSES = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


@dataclasses.dataclass(frozen=True)
class SolverSettings:
    """IPOPT's settings and the derivatives it is given.

    The defaults were measured on the constrained E = 0.05 cruise (80 intervals): IPOPT's monotone barrier took 99
    iterations, the adaptive one 40-70 to the same J (to 1e-6).

    Derivatives: "pointwise" assembles them from the model's pointwise function compiled to C
    (swim_planner.pointwise): 0.44 s for that cruise. "casadi" lets CasADi differentiate the whole NLP graph:
    3.4-3.8 s, 2.6 s of it in the Hessian (66 ms a call); with expand_to_sx it first expands the graph into one
    SX graph, whose Hessian is fast to evaluate (30 ms) but took 9 s to build: 13.7 s in all.

    Attributes
    ----------
    tolerance : float
        IPOPT's tol.
    coarse_grid_tolerance : float
        IPOPT's tol on a coarser grid solved first (``PrimitiveSpec.coarse_intervals``; at least ``tolerance``).
    max_iterations : int
        IPOPT's max_iter.
    print_level : int
        IPOPT's print_level.
    barrier_strategy : str
        IPOPT's mu_strategy: "adaptive" or "monotone".
    expand_to_sx : bool
        Derivatives "casadi" only: CasADi's expand into one SX graph.
    derivatives : str
        "pointwise" or "casadi" (above).

    Raises
    ------
    ValueError
        If derivatives is neither.
    """

    tolerance: float = 1e-8
    coarse_grid_tolerance: float = 1e-6
    # IPOPT's tol on a coarser grid solved first (PrimitiveSpec.coarse_intervals; at least ``tolerance``): its
    # solution only starts the solve on the spec's own grid, which stops at ``tolerance``. Measured on
    # free/decelerate/R0.43/E0.20 (docs/circulatory_primitives.md): its continuation on 20 intervals per second took
    # 3396 IPOPT iterations (105 s) at 1e-8; at 1e-6, with the solve on its 40 per second after it, 2820 (79 s)
    max_iterations: int = 3000
    print_level: int = 0
    barrier_strategy: str = "adaptive"   # IPOPT's mu_strategy: "adaptive" or "monotone"
    expand_to_sx: bool = False           # derivatives "casadi" only: CasADi's expand into one SX graph
    derivatives: str = "pointwise"       # "pointwise" or "casadi" (see above)

    def __post_init__(self) -> None:
        """Check the derivatives setting (Raises, above)."""
        if self.derivatives not in ("pointwise", "casadi"):
            raise ValueError(f"derivatives must be 'pointwise' or 'casadi', got {self.derivatives!r}")


def rest_state(model: VehicleModel, lane_radius_m: float) -> tuple[Array, Array]:
    """The vehicle at rest on a lane: alpha = phi = theta = 0, R = the lane's (free vehicle), qdot = 0.

    Parameters
    ----------
    model : VehicleModel
        The vehicle.
    lane_radius_m : float
        The lane's R, m (the free vehicle's).

    Returns
    -------
    q : (nq,) array
        Positions, rad and m.
    qdot : (nq,) array
        Zero velocities.
    """
    q = np.zeros(model.nq)
    if not model.constrained:
        q[1] = lane_radius_m
    return q, np.zeros(model.nq)


def rest_boundary_state(model: VehicleModel, lane_radius_m: float) -> tuple[Array, ...]:
    """Rest as a boundary state, with the circulatory flow's lag states of still water.

    Parameters
    ----------
    model, lane_radius_m
        As for ``rest_state``; the model's flow decides whether lag states are added.

    Returns
    -------
    tuple of array
        (q (nq,), qdot (nq,)) as ``rest_state``, and with the circulatory flow the lag states (n_lag,) of still
        water, m/s (the steady lag of zero velocity: zero).
    """
    q, qdot = rest_state(model, lane_radius_m)
    if model.circulatory_flow is None:
        return q, qdot
    return q, qdot, model.circulatory_flow.steady_lag(np.zeros(3))


def cruise_mean_speed_m_s(primitive: Primitive) -> float:
    """A cruise's mean speed along its lane.

    Parameters
    ----------
    primitive : Primitive
        A cruise.

    Returns
    -------
    float
        Its mean alpha rate times the lane radius, m/s.
    """
    duration_s = float(primitive.time_s[-1] - primitive.time_s[0])
    return float((primitive.q[-1, 0] - primitive.q[0, 0]) / duration_s * primitive.spec.lane_radius_m)


def cruise_strouhal_number(primitive: Primitive, heave_link_length_m: float) -> float:
    """The Strouhal number 2 A f / U of a cruise's stroke.

    A is the heave amplitude of the pitch axis (half its peak-to-peak excursion across the lane, Lh sin(phi), plus
    R for the free vehicle; swim_model.kinematics), f one stroke per solved cycle, U the mean speed
    (``cruise_mean_speed_m_s``).

    Parameters
    ----------
    primitive : Primitive
        A cruise.
    heave_link_length_m : float
        Lh, m (the rig's).

    Returns
    -------
    float
        2 A f / U, dimensionless.
    """
    spec = primitive.spec
    heave = primitive.q[:, 1] if spec.constrained else primitive.q[:, 2]
    lateral_m = heave_link_length_m * np.sin(heave) - (0.0 if spec.constrained else primitive.q[:, 1])
    amplitude_m = 0.5 * float(lateral_m.max() - lateral_m.min())
    return 2.0 * amplitude_m / spec.solved_duration_s / cruise_mean_speed_m_s(primitive)
