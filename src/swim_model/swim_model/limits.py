"""The rig's joint limits: the record planner, tracker, simulator and bridge all read.

The rig file's ``limits`` section (config/rig.yaml) gives, for the heave and the pitch joint, how far the
planner may move it (planning range), where the bridge starts to scale outward torque down (soft margin inside the
hard stop), where the rig's stop holds it (hard stop), the fastest it can physically turn (max speed) and its torque
limit; and the fastest the hub and the rail can move. Ranges and stops are symmetric about zero.
"""
from __future__ import annotations

import dataclasses

from swim_model.errors import RigConfigError

#: ((heave lower, upper), (pitch lower, upper)) joint stops, rad
HardLimits = tuple[tuple[float, float], tuple[float, float]]


@dataclasses.dataclass(frozen=True)
class JointLimits:
    """One actuated joint's limits, SI units; positions are symmetric about zero (|q| <= value).

    Attributes
    ----------
    planning_range_rad : float
        The planner keeps |q| within this, rad.
    soft_margin_rad : float
        The bridge scales outward torque to zero over this margin inside the hard stop, rad.
    hard_stop_rad : float
        The rig's stop holds |q| at this, rad.
    max_speed_rad_s : float
        The fastest the joint can physically turn, rad/s; a faster counter step is a jump.
    torque_limit_n_m : float
        The largest joint torque the motor gives, N m (paper Sec. 2).
    """

    planning_range_rad: float     # the planner keeps |q| within this
    soft_margin_rad: float        # the bridge scales outward torque to zero over this margin inside the hard stop
    hard_stop_rad: float          # the rig's stop holds |q| at this
    max_speed_rad_s: float        # the fastest the joint can physically turn; faster counter steps are jumps
    torque_limit_n_m: float       # the largest joint torque the motor gives (paper Sec. 2)

    @property
    def hard_stops_rad(self) -> tuple[float, float]:
        """(lower, upper) stop, rad.

        Returns
        -------
        tuple of float
            (-hard_stop_rad, hard_stop_rad).
        """
        return (-self.hard_stop_rad, self.hard_stop_rad)

    def check(self, joint: str) -> None:
        """Check that every value is positive and that range + soft margin <= hard stop.

        Parameters
        ----------
        joint : str
            The joint's name, for the message ("heave", "pitch").

        Raises
        ------
        RigConfigError
            A value not positive, or a soft margin that does not fit between range and stop.
        """
        for field in dataclasses.fields(self):
            if not getattr(self, field.name) > 0.0:
                raise RigConfigError(f"{joint} {field.name} must be positive, got {getattr(self, field.name)}")
        if self.planning_range_rad + self.soft_margin_rad > self.hard_stop_rad:
            raise RigConfigError(
                f"{joint} soft margin ({self.soft_margin_rad} rad) must fit in the gap between its planning range "
                f"({self.planning_range_rad} rad) and its hard stop ({self.hard_stop_rad} rad)")


@dataclasses.dataclass(frozen=True)
class RigLimits:
    """The actuated joints' limits and the largest possible speeds of the passive ones.

    Attributes
    ----------
    heave, pitch : JointLimits
        The heave's and the pitch's limits.
    hub_max_speed_rad_s : float
        The fastest the hub can turn, rad/s.
    rail_max_speed_m_s : float
        The fastest the platform can slide along the rail, m/s.

    Raises
    ------
    RigConfigError
        On construction, for limits that contradict each other (JointLimits.check) or a speed not positive.
    """

    heave: JointLimits
    pitch: JointLimits
    hub_max_speed_rad_s: float    # the fastest the hub can turn
    rail_max_speed_m_s: float     # the fastest the platform can slide along the rail

    def __post_init__(self) -> None:
        """Check the joints' limits and that both speeds are positive (RigConfigError)."""
        self.heave.check("heave")
        self.pitch.check("pitch")
        for name in ("hub_max_speed_rad_s", "rail_max_speed_m_s"):
            if not getattr(self, name) > 0.0:
                raise RigConfigError(f"{name} must be positive, got {getattr(self, name)}")

    @property
    def hard_limits_rad(self) -> HardLimits:
        """Where the rig's stops hold the joints.

        Returns
        -------
        HardLimits
            ((heave lower, upper), (pitch lower, upper)), rad.
        """
        return (self.heave.hard_stops_rad, self.pitch.hard_stops_rad)

    @property
    def soft_margins_rad(self) -> tuple[float, float]:
        """The soft-limit margins inside the hard stops.

        Returns
        -------
        (float, float)
            The heave's and the pitch's margin, rad.
        """
        return (self.heave.soft_margin_rad, self.pitch.soft_margin_rad)

    @property
    def torque_limits_n_m(self) -> tuple[float, float]:
        """The joint torque limits.

        Returns
        -------
        tuple of float
            (heave, pitch), N m.
        """
        return (self.heave.torque_limit_n_m, self.pitch.torque_limit_n_m)

    @property
    def max_speeds(self) -> tuple[float, float, float, float]:
        """The physically possible joint speeds.

        Returns
        -------
        tuple of float
            (alpha rad/s, R m/s, phi rad/s, theta rad/s).
        """
        return (self.hub_max_speed_rad_s, self.rail_max_speed_m_s, self.heave.max_speed_rad_s,
                self.pitch.max_speed_rad_s)
