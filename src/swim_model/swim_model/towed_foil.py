"""The towed oscillating foil: the flume experiment run on the reduced flow model or on the vortex wake.

Kinematics (Anderson, Streitlien, Barrett & Triantafyllou, J. Fluid Mech. 360, 1998): a carriage tows the pivot at
``speed_m_s`` along +X of the tank frame; the pivot heaves ``h = h0 sin(w t)`` along +Y and the foil pitches about it,
``theta = theta0 sin(w t + psi)``, theta the chord's angle from +X, counter-clockwise (leading edge toward +Y). The
chord points along +X at theta = 0, so the foil moves leading edge first; psi = 90 deg (pitch leading heave) turns
the nose along the path and makes thrust. The pivot sits ``pivot_from_leading_edge_m`` behind the leading edge.

Definitions, as the paper's:
* Strouhal number ``St = 2 h0 f / U`` (the heave's peak-to-peak excursion as the wake width).
* Angle of attack at the pivot: ``atan2(-V_P, U_P)`` of the pivot's velocity (U, h') in foil axes, which is
  ``theta - atan(h'/U)``; at the instant of largest heave velocity (t = 0, where theta = theta0 for psi = 90 deg)
  it is ``theta0 - atan(pi St)``, the paper's ``-alpha0`` (its nominal maximum angle of attack, same size).
* Thrust ``T``: the mean fluid force along +X; ``C_T = T / (1/2 rho U^2 c s)``.
* Input power ``P``: the mean power the heave and pitch drives put in, ``-(F_Y h' + M_P theta')`` (M_P about the
  pivot), which is ``-(F . v_F + M_F Omega) + F_X U``; efficiency ``eta = T U / P``.

The project's own angle of attack (``peak_angle_of_attack_rad``) is ``atan2(-V, U)`` at the foil frame's origin F
(the map origin, near mid-chord: eq. 40's U, V); the pivot's is reported beside it.

Fluid force: the added-mass (Kirchhoff) force of the ideal model, eq. 46, from the prescribed foil velocity and
its rate, plus either the circulatory model of ``flow.py`` (its lag states integrated by RK4 with the motion
prescribed, started from the steady state of the initial velocity), or the vortical force of ``wake.py`` plus the
same profile drag. The means are taken over the last ``averaged_cycles`` whole cycles; over whole cycles the added
mass contributes nothing to either mean (it is the derivative of a periodic impulse and energy).
"""
from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from swim_model.errors import FlowModelError
from swim_model.joukowski import AddedMass, JoukowskiFoil
from swim_model.wake import Wake, WakeParameters

if TYPE_CHECKING:
    from swim_model.flow import FlowParameters

Array = npt.NDArray[np.float64]

WATER_DENSITY_KG_M3 = 998.2  # fresh water at 20 C, as rig.yaml
# numerical settings (assumed, each with its reason)
REDUCED_MIN_STEPS_PER_CYCLE = 200          # 200 samples resolve the forces' harmonics for the cycle means
REDUCED_MAX_TRAVEL_PER_STEP_CHORDS = 0.1   # cycle means within 1e-5 of those with 2000 steps a cycle
REDUCED_STARTUP_CHORDS = 30.0              # Jones's slow lag decays as e^{-0.0455 s}: 6 % left after 30 chords
# the wake's cycle means converge in the steps per cycle, not in the trailing edge's travel per step: at Anderson's
# St 0.22-0.50 (h0/c 0.75) C_T falls 3-6 % from 200 to 1600 steps a cycle, and 800 are within 1 % of 1600
# (docs/flow_model.md, "The wake's time step"); the efficiency moves by 0.003 at most
WAKE_MIN_STEPS_PER_CYCLE = 800
WAKE_MAX_TRAVEL_PER_STEP_CHORDS = 1.0 / 30.0  # the trailing edge's travel per shed vortex, as test_wake.py
WAKE_STARTUP_CHORDS = 8.0                  # the starting vortex is 8 chords behind before averaging starts
# the towed foil's trailing edge never rests (it moves at the towing speed at least), so the least shedding distance
# only keeps a new vortex off the cusp: a ten-thousandth of the chord, under half the trailing edge's travel in a
# step at 1600 steps a cycle up to k = 8. The wake's own default, sized for the closed loop's 8 ms step where the
# foil does rest, would set the shedding distance of these short steps instead of the travel (docs/flow_model.md,
# "The wake's time step")
WAKE_MIN_SHED_DISTANCE_CHORDS = 1.0e-4


@dataclasses.dataclass(frozen=True)
class TowedFoilKinematics:
    """Prescribed heave and pitch of a towed foil (kinematics: the module docstring).

    Attributes
    ----------
    speed_m_s : float
        Towing speed U along +X, m/s.
    heave_amplitude_m : float
        h0 of h = h0 sin(w t), m.
    pitch_amplitude_rad : float
        theta0 of theta = theta0 sin(w t + psi), rad.
    frequency_hz : float
        f = w / (2 pi), Hz.
    phase_rad : float
        psi, pitch ahead of heave, rad.
    pivot_x_m : float
        The pivot's x in the foil frame (x toward the leading edge from the map origin), m.
    """

    speed_m_s: float
    heave_amplitude_m: float
    pitch_amplitude_rad: float
    frequency_hz: float
    phase_rad: float
    pivot_x_m: float  # the pivot's x in the foil frame (x toward the leading edge from the map origin)

    @property
    def omega_rad_s(self) -> float:
        """Angular frequency w = 2 pi f, rad/s."""
        return 2.0 * math.pi * self.frequency_hz

    def heave(self, t: Array) -> tuple[Array, Array, Array]:
        """The heave and its first two derivatives.

        Parameters
        ----------
        t : (n,) ndarray
            Times, s.

        Returns
        -------
        tuple of three (n,) ndarray
            (h m, h' m/s, h'' m/s^2).
        """
        w = self.omega_rad_s
        return (self.heave_amplitude_m * np.sin(w * t), self.heave_amplitude_m * w * np.cos(w * t),
                -self.heave_amplitude_m * w * w * np.sin(w * t))

    def pitch(self, t: Array) -> tuple[Array, Array, Array]:
        """The pitch angle and its first two derivatives.

        Parameters
        ----------
        t : (n,) ndarray
            Times, s; the pitch is psi ahead of the heave at each.

        Returns
        -------
        tuple of three (n,) ndarray
            (theta rad, theta' rad/s, theta'' rad/s^2).
        """
        w = self.omega_rad_s
        arg = w * t + self.phase_rad
        return (self.pitch_amplitude_rad * np.sin(arg), self.pitch_amplitude_rad * w * np.cos(arg),
                -self.pitch_amplitude_rad * w * w * np.sin(arg))

    def pose(self, t: Array) -> tuple[Array, Array, Array]:
        """The foil frame's origin F and the chord's angle in the tank frame.

        Parameters
        ----------
        t : (n,) ndarray
            Times since the tow began (the pivot at X = 0 at t = 0), s.

        Returns
        -------
        tuple of three (n,) ndarray
            (X m, Y m, theta rad).
        """
        h, _, _ = self.heave(t)
        theta, _, _ = self.pitch(t)
        return (self.speed_m_s * t - self.pivot_x_m * np.cos(theta), h - self.pivot_x_m * np.sin(theta), theta)

    def velocity(self, t: Array) -> Array:
        """The velocity of F in foil axes (eq. 40's frame).

        Parameters
        ----------
        t : (n,) ndarray
            Times, s, at which F's velocity is taken.

        Returns
        -------
        (n, 3) ndarray
            (U m/s, V m/s, Omega rad/s).
        """
        _, hd, _ = self.heave(t)
        theta, thetad, _ = self.pitch(t)
        c, s = np.cos(theta), np.sin(theta)
        u = self.speed_m_s * c + hd * s
        v = -self.speed_m_s * s + hd * c - self.pivot_x_m * thetad
        return np.column_stack([u, v, thetad])

    def acceleration(self, t: Array) -> Array:
        """The rate of (U, V, Omega), components in the turning foil axes.

        Parameters
        ----------
        t : (n,) ndarray
            Times, s: the rates are exact derivatives, not differences.

        Returns
        -------
        (n, 3) ndarray
            (U' m/s^2, V' m/s^2, Omega' rad/s^2).
        """
        _, hd, hdd = self.heave(t)
        theta, thetad, thetadd = self.pitch(t)
        c, s = np.cos(theta), np.sin(theta)
        along = self.speed_m_s * c + hd * s        # pivot velocity . chord
        across = -self.speed_m_s * s + hd * c      # pivot velocity . normal
        return np.column_stack([hdd * s + thetad * across, hdd * c - thetad * along - self.pivot_x_m * thetadd,
                                thetadd])

    def pivot_velocity(self, t: Array) -> Array:
        """The pivot's velocity in foil axes.

        Parameters
        ----------
        t : (n,) ndarray
            Times, s, at which the pivot's velocity is taken.

        Returns
        -------
        (n, 2) ndarray
            (U_P, V_P), m/s.
        """
        _, hd, _ = self.heave(t)
        theta, _, _ = self.pitch(t)
        c, s = np.cos(theta), np.sin(theta)
        return np.column_stack([self.speed_m_s * c + hd * s, -self.speed_m_s * s + hd * c])


def kirchhoff_force(added: AddedMass, velocity: Array, acceleration: Array) -> Array:
    """The ideal model's added-mass force and moment (eq. 46) in foil axes at F.

    Parameters
    ----------
    added : AddedMass
        The foil's added mass.
    velocity : (n, 3) ndarray
        (U m/s, V m/s, Omega rad/s) of F in foil axes.
    acceleration : (n, 3) ndarray
        Its rate, m/s^2 and rad/s^2.

    Returns
    -------
    (n, 3) ndarray
        (Fx N, Fy N, tau_z N m).

    References
    ----------
    Saimek & Li (2004), eq. 46.
    """
    u, v, w = velocity.T
    ud, vd, wd = acceleration.T
    return np.column_stack([-added.m11 * ud + added.m22 * w * v + added.m26 * w * w,
                            -added.m22 * vd - added.m26 * wd - added.m11 * w * u,
                            -added.m26 * vd - added.m66 * wd - added.m26 * w * u + (added.m11 - added.m22) * u * v])


@dataclasses.dataclass(frozen=True)
class OscillatingFoilResult:
    """Cycle means and time series of a towed oscillating foil (signs and definitions: the module docstring).

    Attributes
    ----------
    model : str
        "circulatory" or "wake".
    mean_thrust_n : float
        Mean fluid force along +X, N.
    mean_power_w : float
        Mean power the heave and pitch drives put in, W.
    thrust_coefficient : float
        T / (1/2 rho U^2 c s).
    power_coefficient : float
        P / (1/2 rho U^3 c s).
    efficiency : float
        T U / P.
    strouhal : float
        2 h0 f / U.
    reduced_frequency : float
        w c / (2 U).
    peak_angle_of_attack_rad : float
        Largest |atan2(-V, U)| at the foil frame's origin, rad.
    peak_angle_of_attack_at_pivot_rad : float
        The same at the pivot, rad.
    lift_amplitude_n : float
        First harmonic of the force along +Y, N.
    mean_lift_n : float
        Mean force along +Y, N.
    peak_leading_edge_suction_parameter : float
        Largest |A0| over the averaged cycles, the leading-edge suction parameter before its cap
        (swim_model.leading_edge).
    min_attached_weight : float
        The reduced model's smallest attached-flow weight w (1 attached, 0 stalled; 1 for the wake, whose flow
        never stalls).
    peak_free_stream_suction_parameter : float
        Largest |A0 |u| / U|: the same parameter referred to the towing speed U instead of the foil's own speed
        |u|, as Ramesh et al. (JFM 751, 2014) refer theirs to the free stream.
    peak_three_quarter_chord_incidence_rad : float
        Largest |atan2(Q, U)|, Q the normal velocity at the three-quarter chord (heave, pitch and pitch rate, no
        lag): the quasi-steady incidence there, rad.
    cycles, averaged_cycles, steps_per_cycle : int
        Cycles simulated, cycles averaged (the last ones), time steps per cycle.
    time_s, thrust_n, lift_n, power_w, angle_of_attack_rad : (n,) ndarray
        Series over the averaged cycles: s, N, N, W, rad.
    heave_power_w : (n,) ndarray
        The heave drive's share of power_w, -F_Y h', W; the rest, power_w - heave_power_w, is the pitch drive's
        (M_P theta' about the pivot).
    leading_edge_suction_parameter : (n,) ndarray
        A0 over the averaged cycles (before the reduced model's cap), dimensionless.
    """

    model: str
    mean_thrust_n: float
    mean_power_w: float
    thrust_coefficient: float
    power_coefficient: float
    efficiency: float
    strouhal: float
    reduced_frequency: float
    peak_angle_of_attack_rad: float
    peak_angle_of_attack_at_pivot_rad: float
    lift_amplitude_n: float
    mean_lift_n: float
    peak_leading_edge_suction_parameter: float
    min_attached_weight: float
    peak_free_stream_suction_parameter: float
    peak_three_quarter_chord_incidence_rad: float
    cycles: int
    averaged_cycles: int
    steps_per_cycle: int
    time_s: Array = dataclasses.field(repr=False)
    thrust_n: Array = dataclasses.field(repr=False)
    lift_n: Array = dataclasses.field(repr=False)
    power_w: Array = dataclasses.field(repr=False)
    angle_of_attack_rad: Array = dataclasses.field(repr=False)
    heave_power_w: Array = dataclasses.field(repr=False)
    leading_edge_suction_parameter: Array = dataclasses.field(repr=False)


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise FlowModelError(f"oscillating_foil: {name} must be positive and finite, got {value!r}")
    return value


def oscillating_foil(  # noqa: C901 - the public entry: each keyword checked, then the wake run or the reduced run
        foil: JoukowskiFoil, speed_m_s: float, heave_amplitude_m: float, pitch_amplitude_rad: float,
        frequency_hz: float, phase_rad: float, pivot_from_leading_edge_m: float,
        model: str = "circulatory", cycles: int | None = None, *, averaged_cycles: int = 2,
        steps_per_cycle: int | None = None, water_density_kg_m3: float = WATER_DENSITY_KG_M3,
        flow_parameters: "FlowParameters | None" = None,
        wake_parameters: WakeParameters | None = None) -> OscillatingFoilResult:
    """Tow the foil at constant speed while it heaves and pitches; return thrust, power and efficiency.

    Parameters
    ----------
    foil : JoukowskiFoil
        The foil (its chord and span set the coefficients' reference area c s).
    speed_m_s : float
        Towing speed U > 0, m/s.
    heave_amplitude_m : float
        h0 >= 0 of h = h0 sin(w t), m.
    pitch_amplitude_rad : float
        theta0 of theta = theta0 sin(w t + phase), rad.
    frequency_hz : float
        f > 0, Hz.
    phase_rad : float
        psi, pitch ahead of heave, rad (pi/2 makes thrust).
    pivot_from_leading_edge_m : float
        Pitch axis position behind the leading edge along the chord, m.
    model : {"circulatory", "wake"}, optional
        flow.py's reduced model, or wake.py's vortices plus flow.py's profile drag.
    cycles : int, optional
        Total cycles simulated (default: enough start-up cycles to travel 30 chords for the reduced model, 8 for
        the wake, at least 2, plus ``averaged_cycles``).
    averaged_cycles : int, optional
        The last cycles, averaged.
    steps_per_cycle : int, optional
        Time steps per cycle (default: the module's REDUCED_/WAKE_ constants).
    water_density_kg_m3 : float, optional
        rho, kg/m^3.
    flow_parameters : FlowParameters, optional
        The reduced model's coefficients (the wake uses its profile drag coefficient, its leading edge's critical
        suction, and with ``separation`` set its separation point, from its lag states under the same motion).
    wake_parameters : WakeParameters, optional
        The wake's numerical parameters (default: WakeParameters with room for one cycle of unmerged vortices).

    Returns
    -------
    OscillatingFoilResult
        Cycle means and the averaged cycles' series.

    Raises
    ------
    FlowModelError
        For an unknown model, a non-positive speed or frequency, or cycle and step counts that cannot be run.

    References
    ----------
    Anderson, Streitlien, Barrett & Triantafyllou, J. Fluid Mech. 360 (1998): the experiment and its definitions.
    """
    from swim_model.flow import CirculatoryFlow, FlowParameters

    if model not in ("circulatory", "wake"):
        raise FlowModelError(f"oscillating_foil: model must be 'circulatory' or 'wake', got {model!r}")
    speed = _positive("speed_m_s", speed_m_s)
    frequency = _positive("frequency_hz", frequency_hz)
    rho = _positive("water_density_kg_m3", water_density_kg_m3)
    for name, value in (("heave_amplitude_m", heave_amplitude_m), ("pitch_amplitude_rad", pitch_amplitude_rad),
                        ("phase_rad", phase_rad), ("pivot_from_leading_edge_m", pivot_from_leading_edge_m)):
        if not math.isfinite(float(value)):
            raise FlowModelError(f"oscillating_foil: {name} must be finite, got {value!r}")
    if heave_amplitude_m < 0.0:
        raise FlowModelError("oscillating_foil: heave_amplitude_m must be >= 0")
    if averaged_cycles < 1:
        raise FlowModelError("oscillating_foil: averaged_cycles must be at least 1")
    flow = CirculatoryFlow(foil, rho, flow_parameters or FlowParameters())
    chord = flow.chord_m
    kinematics = TowedFoilKinematics(speed, float(heave_amplitude_m), float(pitch_amplitude_rad), frequency,
                                     float(phase_rad), foil.leading_edge_x_m - float(pivot_from_leading_edge_m))
    period = 1.0 / frequency

    # the trailing edge's path through the water over one cycle sets the resolution
    t_cycle = np.linspace(0.0, period, 400, endpoint=False)
    nu_cycle = kinematics.velocity(t_cycle)
    te_path_m = float(np.mean(np.hypot(nu_cycle[:, 0], nu_cycle[:, 1] + nu_cycle[:, 2] * foil.trailing_edge_x_m))
                      * period)
    wake_model = model == "wake"
    if steps_per_cycle is None:
        minimum, travel = ((WAKE_MIN_STEPS_PER_CYCLE, WAKE_MAX_TRAVEL_PER_STEP_CHORDS) if wake_model else
                           (REDUCED_MIN_STEPS_PER_CYCLE, REDUCED_MAX_TRAVEL_PER_STEP_CHORDS))
        steps_per_cycle = max(minimum, math.ceil(te_path_m / (travel * chord)))
    if steps_per_cycle < 8:
        raise FlowModelError("oscillating_foil: steps_per_cycle must be at least 8")
    if cycles is None:
        startup = WAKE_STARTUP_CHORDS if wake_model else REDUCED_STARTUP_CHORDS
        cycles = max(2, math.ceil(startup * chord / (speed * period))) + averaged_cycles
    if cycles <= averaged_cycles:
        raise FlowModelError(f"oscillating_foil: cycles ({cycles}) must exceed averaged_cycles ({averaged_cycles})")
    dt = period / steps_per_cycle
    total_steps = cycles * steps_per_cycle
    averaged_steps = averaged_cycles * steps_per_cycle
    # the reduced model's lag states at every step's end under the prescribed motion (the wake takes its separation
    # point from them, and needs none without one)
    half_step_velocities = kinematics.velocity(np.arange(2 * total_steps + 1, dtype=float) * (0.5 * dt))
    lag = (flow.integrate_lag(half_step_velocities, dt, flow.steady_lag(half_step_velocities[0]))
           if not wake_model or flow.params.separates else None)

    if wake_model:
        params = wake_parameters or WakeParameters(
            rho_kg_m3=rho, max_vortex_count=max(300, steps_per_cycle + 100),
            protected_vortex_count=steps_per_cycle + 50, min_shed_distance_m=WAKE_MIN_SHED_DISTANCE_CHORDS * chord,
            critical_leading_edge_suction=flow.params.critical_leading_edge_suction,
            suction_cap_exponent=flow.params.suction_cap_exponent,
            speed_regularization_m_s=flow.params.speed_regularization_m_s)
        wake = Wake(foil, params)
        steps = np.arange(1, total_steps + 1, dtype=float)
        x, y, theta = kinematics.pose(steps * dt)
        nu_end = kinematics.velocity(steps * dt)
        # the trailing edge's separation point at each step's end: the reduced model's, from its lag states under
        # the same motion (1 throughout without FlowParameters.separation)
        separation_point = (np.ones(total_steps) if lag is None else
                            np.asarray(flow.evaluate(half_step_velocities[2::2], lag[1:])["separation_point"],
                                       dtype=float))
        vortical = np.zeros((total_steps, 3))
        suction_parameter = np.zeros(averaged_steps)
        for i in range(total_steps):
            force = wake.step(dt, (x[i], y[i], theta[i]), (nu_end[i, 0], nu_end[i, 1], nu_end[i, 2]),
                              float(separation_point[i]))
            vortical[i] = (force.fx_n, force.fy_n, force.moment_n_m)
            if i >= total_steps - averaged_steps:
                suction_parameter[i - total_steps + averaged_steps] = wake.leading_edge_suction_parameter()
        attached_weight = np.ones(1)
        time = (steps - 0.5) * dt          # the wake's force belongs to the middle of its step
        window = slice(total_steps - averaged_steps, total_steps)
        suction_speed = np.hypot(nu_end[window, 0], nu_end[window, 1])   # A0 is taken at each step's end
        time = time[window]
        velocity = kinematics.velocity(time)
        drag = np.asarray(flow.functions["profile_drag"].map(time.size)(velocity.T), dtype=float).T
        fluid = vortical[window] + drag
    else:
        window = slice(total_steps - averaged_steps, total_steps)
        time = np.arange(total_steps + 1, dtype=float)[window] * dt
        velocity = half_step_velocities[0::2][window]
        assert lag is not None   # integrated for the reduced model
        terms = flow.evaluate(velocity, lag[window])
        fluid, suction_parameter, attached_weight = terms["f"], terms["lesp"], terms["attached_weight"]
        suction_speed = np.hypot(velocity[:, 0], velocity[:, 1])
    force = fluid + kirchhoff_force(flow.added_mass, velocity, kinematics.acceleration(time))

    _, _, theta = kinematics.pose(time)
    c, s = np.cos(theta), np.sin(theta)
    thrust = force[:, 0] * c - force[:, 1] * s
    lift = force[:, 0] * s + force[:, 1] * c
    power = -np.sum(force * velocity, axis=1) + thrust * speed
    angle = np.arctan2(-velocity[:, 1], velocity[:, 0])
    _, heave_rate, _ = kinematics.heave(time)
    heave_power = -lift * heave_rate
    pivot = kinematics.pivot_velocity(time)
    pivot_angle = np.arctan2(-pivot[:, 1], pivot[:, 0])
    # the quasi-steady incidence at the three-quarter chord, and A0 referred to the towing speed
    normal_34 = -(velocity[:, 1] + velocity[:, 2] * flow.three_quarter_chord_x_m)
    incidence_34 = np.arctan2(normal_34, velocity[:, 0])
    free_stream_suction = suction_parameter * suction_speed / speed
    mean_thrust, mean_power = float(np.mean(thrust)), float(np.mean(power))
    reference_force = 0.5 * rho * speed ** 2 * chord * foil.span_m
    harmonic = 2.0 * np.mean(lift * np.exp(-1j * kinematics.omega_rad_s * time))
    return OscillatingFoilResult(
        model=model, mean_thrust_n=mean_thrust, mean_power_w=mean_power,
        thrust_coefficient=mean_thrust / reference_force, power_coefficient=mean_power / (reference_force * speed),
        efficiency=mean_thrust * speed / mean_power if mean_power != 0.0 else float("nan"),
        strouhal=2.0 * heave_amplitude_m * frequency / speed,
        reduced_frequency=kinematics.omega_rad_s * chord / (2.0 * speed),
        peak_angle_of_attack_rad=float(np.max(np.abs(angle))),
        peak_angle_of_attack_at_pivot_rad=float(np.max(np.abs(pivot_angle))),
        lift_amplitude_n=float(abs(harmonic)), mean_lift_n=float(np.mean(lift)),
        peak_leading_edge_suction_parameter=float(np.max(np.abs(suction_parameter))),
        min_attached_weight=float(np.min(attached_weight)),
        peak_free_stream_suction_parameter=float(np.max(np.abs(free_stream_suction))),
        peak_three_quarter_chord_incidence_rad=float(np.max(np.abs(incidence_34))),
        cycles=int(cycles), averaged_cycles=int(averaged_cycles), steps_per_cycle=int(steps_per_cycle),
        time_s=time, thrust_n=thrust, lift_n=lift, power_w=power, angle_of_attack_rad=angle,
        heave_power_w=heave_power, leading_edge_suction_parameter=np.asarray(suction_parameter, dtype=float))
