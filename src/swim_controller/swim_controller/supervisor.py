"""What the tracker node does between plans and around the law: modes, tolerances, stale state, cancel.

Modes: IDLE (no plan yet: zero torque), TRACKING (the cascade law on the active plan), HOLDING (after a
plan ended or was canceled: the foil held still at its last heave and pitch), STOPPED (the state went
stale: zero torque until a fresh state arrives, then IDLE). Plan time runs on the state messages' own
clock (their stamps), so a lock-step simulator and a real-time rig look the same to the law.
"""
from __future__ import annotations

import dataclasses
import enum
import math
from typing import Optional

import numpy as np
import numpy.typing as npt

from swim_control.trajectory import Trajectory
from swim_controller.tracker import CascadeTracker, ControlOutput

Array = npt.NDArray[np.float64]


class Mode(enum.Enum):
    """What the supervisor commands: IDLE, TRACKING, HOLDING or STOPPED (module docstring)."""

    IDLE = "idle"
    TRACKING = "tracking"
    HOLDING = "holding"
    STOPPED = "stopped"


class Outcome(enum.Enum):
    """How a plan's execution ended (the action's result codes map one to one)."""

    SUCCEEDED = "succeeded"
    PATH_TOLERANCE_VIOLATED = "path tolerance violated"
    GOAL_TOLERANCE_VIOLATED = "goal tolerance violated"
    STATE_LOST = "state lost"
    PREEMPTED = "preempted"
    CANCELED = "canceled"


@dataclasses.dataclass
class Step:
    """One period's command and report.

    Attributes
    ----------
    torque : (2,) array
        The commanded (heave, pitch) torque, N m, after saturation.
    saturated : tuple of bool
        Whether the (heave, pitch) command was clipped at its motor limit.
    output : ControlOutput or None
        The tracking law's result; None unless TRACKING.
    outcome : Outcome or None
        Set on the period the plan's execution ended, else None.
    """

    torque: Array
    saturated: tuple[bool, bool]
    output: Optional[ControlOutput]   # None unless TRACKING
    outcome: Optional[Outcome]        # set on the period the plan's execution ended


@dataclasses.dataclass(frozen=True)
class Tolerances:
    """Limits on the tracking errors, checked every period; 0 means not checked.

    Attributes
    ----------
    path_alpha_rad : float
        Largest |alpha error| along the plan, rad, >= 0.
    path_r_m : float
        Largest |R error| along the plan, m, >= 0 (the free vehicle).
    goal_alpha_rad : float
        Largest |alpha error| at the plan's end, rad, >= 0.
    goal_r_m : float
        Largest |R error| at the plan's end, m, >= 0 (the free vehicle).
    """

    path_alpha_rad: float = 0.0
    path_r_m: float = 0.0
    goal_alpha_rad: float = 0.0
    goal_r_m: float = 0.0

    def validate(self) -> None:
        """Check the tolerances.

        A zero tolerance switches its check off.

        Raises
        ------
        ValueError
            If a tolerance is negative or not finite.
        """
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"tolerance {field.name} must be finite and >= 0, got {value!r}")


def _violates(error: float, tolerance: float) -> bool:
    return tolerance > 0.0 and abs(error) > tolerance


class Supervisor:
    """Runs one plan at a time through a CascadeTracker; owns no ROS objects and no clock.

    Parameters
    ----------
    tracker : CascadeTracker
        The tracking law the plans run through.

    Attributes
    ----------
    mode : Mode
        What the supervisor commands now.
    tolerances : Tolerances
        The active plan's limits on the tracking errors.
    last_errors : tuple of float
        (alpha error, rad; R error, m) at the last tracked period.
    elapsed_s : float
        Plan time of the last tracked period, s.
    """

    def __init__(self, tracker: CascadeTracker) -> None:
        self.tracker = tracker
        self.mode = Mode.IDLE
        self.tolerances = Tolerances()
        self._start_time_s: Optional[float] = None
        self._hold_target: Optional[Array] = None
        self.last_errors: tuple[float, float] = (0.0, 0.0)   # alpha, R at the last tracked period
        self.elapsed_s = 0.0

    def begin(self, trajectory: Trajectory, tolerances: Tolerances = Tolerances()) -> None:
        """Start tracking a plan at the next state (its stamp is plan time 0).

        Parameters
        ----------
        trajectory : Trajectory
            The plan.
        tolerances : Tolerances, optional
            Its limits on the tracking errors (default: none checked).

        Raises
        ------
        ValueError
            If a tolerance is negative or not finite.
        PlanError
            If the plan's flow model is not the tracker's.
        """
        tolerances.validate()
        self.tracker.start(trajectory)
        self.tolerances = tolerances
        self._start_time_s = None
        self.mode = Mode.TRACKING
        self.last_errors = (0.0, 0.0)
        self.elapsed_s = 0.0

    def cancel(self, q: Optional[Array]) -> None:
        """Stop the plan and hold the foil where it is.

        Parameters
        ----------
        q : (nq,) array or None
            The last measured positions (rad, m); None: no state yet, so go IDLE (zero torque).
        """
        if q is not None:
            self._hold_target = np.array(q[-2:], dtype=float)
            self.mode = Mode.HOLDING
        else:
            self.mode = Mode.IDLE

    def state_lost(self) -> None:
        """No fresh state: command zero torque until states come back."""
        self.mode = Mode.STOPPED

    def on_state(self, time_s: float, q: Array, qdot: Array) -> Step:
        """The command for the period that starts with this (validated) state.

        Parameters
        ----------
        time_s : float
            The state's stamp, s: plan time is measured from the first state after ``begin``.
        q, qdot : (nq,) array
            The validated measured state: positions (rad, m), velocities (rad/s, m/s).

        Returns
        -------
        Step
            The torque, saturation, the law's output (TRACKING) and the outcome, if the plan ended.
        """
        if self.mode is Mode.STOPPED:
            self.mode = Mode.IDLE   # fresh state again: stay passive until a new plan
        if self.mode is Mode.IDLE:
            return Step(np.zeros(2), (False, False), None, None)
        if self.mode is Mode.HOLDING:
            assert self._hold_target is not None   # set with HOLDING
            torque, saturated = self.tracker.hold(q, qdot, self._hold_target)
            return Step(torque, saturated, None, None)
        if self._start_time_s is None:
            self._start_time_s = time_s
        plan_time_s = time_s - self._start_time_s
        output = self.tracker.step(plan_time_s, q, qdot)
        trajectory = self.tracker.trajectory
        assert trajectory is not None   # TRACKING: begin() started the tracker on it
        lateral_error = float(q[1] - output.reference.q[1]) if trajectory.ny == 2 else 0.0
        errors = (float(q[0] - output.reference.q[0]), lateral_error)
        self.last_errors = errors
        self.elapsed_s = plan_time_s
        outcome = None
        if _violates(errors[0], self.tolerances.path_alpha_rad) or _violates(errors[1], self.tolerances.path_r_m):
            outcome = Outcome.PATH_TOLERANCE_VIOLATED
        elif output.holding:
            goal_missed = (_violates(errors[0], self.tolerances.goal_alpha_rad)
                           or _violates(errors[1], self.tolerances.goal_r_m))
            outcome = Outcome.GOAL_TOLERANCE_VIOLATED if goal_missed else Outcome.SUCCEEDED
        if outcome is not None:
            self._hold_target = trajectory.q[-1, -2:].copy() if outcome is Outcome.SUCCEEDED else q[-2:].copy()
            self.mode = Mode.HOLDING
            if outcome is not Outcome.SUCCEEDED:
                torque, saturated = self.tracker.hold(q, qdot, self._hold_target)
                return Step(torque, saturated, output, outcome)
        return Step(output.torque, output.saturated, output, outcome)


class StaleStateWatch:
    """Is the newest state older than limit_s? Asked every check_period_s by a timer.

    A check that comes more than late_periods check periods after the one before means the asker itself was held
    up (its process did not run, or a callback held its executor): states that arrived meanwhile are still unread,
    so that check does not judge. At most one check in a row is skipped, so a dead plant is caught on a host that
    is always late, at most one check period later than on time.

    Parameters
    ----------
    now_s : float
        The time the watch starts, s, on any monotonic clock (all times here are on it).
    check_period_s : float
        The period of the checks, s.
    late_periods : float, optional
        A check more than this many check periods after the one before does not judge.

    Attributes
    ----------
    last_state_s : float
        When the newest state arrived, s.
    check_gap_s : float
        The time between the last check and the one before it, s (what tells a stalled asker from a silent
        plant in a report).
    """

    def __init__(self, now_s: float, check_period_s: float, late_periods: float = 3.0) -> None:
        self.check_period_s = check_period_s
        self.late_periods = late_periods
        self.last_state_s = now_s
        self._last_check_s = now_s
        self._skipped = False
        self.check_gap_s = 0.0

    def state_arrived(self, now_s: float) -> None:
        """Record a state's arrival.

        Parameters
        ----------
        now_s : float
            The time it arrived, s.
        """
        self.last_state_s = now_s

    def stale(self, now_s: float, limit_s: float) -> bool:
        """The check: whether no state arrived within limit_s of now_s.

        Parameters
        ----------
        now_s : float
            The time of this check, s.
        limit_s : float
            The largest age of the newest state, s.

        Returns
        -------
        bool
            True if the state is stale and this check may judge (it did not come late).
        """
        self.check_gap_s = now_s - self._last_check_s
        came_late = self.check_gap_s > self.late_periods * self.check_period_s
        skip = came_late and not self._skipped
        self._last_check_s, self._skipped = now_s, skip
        return not skip and now_s - self.last_state_s > limit_s
