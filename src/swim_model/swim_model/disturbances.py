"""What the ideal-flow model leaves out (paper Sec. 7 names them as the rig's disturbances), as forces.

Every disturbance is a generalized force on q = (alpha, [R,] phi, theta):

- friction in the hub (alpha) and the rails (R): viscous b qdot plus Coulomb with stiction (a coordinate at rest
  stays at rest while the force needed to hold it is below the static limit; the paper saw the lateral velocity
  stick at 0, Sec. 7.3), handled by the plant's stick-slip logic (swim_model.plant);
- quadratic drag on the foil, F = -1/2 rho Cd A |v| v on its chordwise (U) and normal (V) velocities in the foil
  frame, A = chord x span, mapped to q by Q2(q)' (eq. 40), and on the platform's parts that move in water
  (tangential R alphadot, radial Rdot);
- a platform not quite level: gravity's in-plane component m g sin(tilt) along the tilt direction beta acts on the
  platform's mass at radius R: Q_alpha = m g sin(tilt) R sin(alpha - beta), Q_R = -m g sin(tilt) cos(alpha - beta);
- surface waves whose force grows with speed: band-limited noise on the foil's normal force with standard deviation
  wave_force_per_speed2 |v_foil|^2 (first-order filtered white noise, seeded);
- encoder quantization and measurement noise are the simulator's sensors' (swim_sim.sensors).

Two sets of sizes. The defaults (``Disturbances()``) are the physical ones: bearing friction from the bearings'
published friction coefficients and the loads of the shipped rig file, the foil's drag from a flat plate's and a
laminar section's coefficients, a platform levelled with a spirit level, waves of a small tank; each constant
below names its source or the reason it was assumed (docs/disturbances.md puts them side by side).
``Disturbances.paper()`` are the small sizes the ideal-flow plans survive, which the paper's pipeline
(swim_bringup's config/paper) runs with. ``Disturbances.separation_drag()`` is the foil's drag alone, what a vehicle
in the vortex wake's water adds to the wake (swim_model.wake_coupling).
"""
from __future__ import annotations

import dataclasses
import math

from swim_model import load_rig
from swim_model.flow import KINEMATIC_VISCOSITY_WATER_M2_S, laminar_profile_drag_coefficient

GRAVITY_M_S2 = 9.80665

#: the shipped rig file (swim_model config/rig.yaml): the masses, lane radius, foil and tank the sizes below are
#: computed from; a rig of other masses needs its own sizes (sim_node's disturbances.* parameters)
_RIG = load_rig()

# --- bearing friction: frictional moment M = mu P d / 2 (P the bearing load, d the bore; SKF, below) ------------
#: SKF Rolling bearings catalogue, "Friction": constant coefficient of friction of open deep groove ball bearings
#: (the estimate M = 0.5 mu P d); Koyo's catalogue gives 0.0010-0.0015 for the same type
DEEP_GROOVE_BALL_BEARING_FRICTION = 0.0015
#: a rolling bearing's start-up friction is up to twice its running friction (roymech.org, Rolling bearing friction)
ROLLING_BEARING_BREAKAWAY_RATIO = 2.0
#: assumed: the hub turns on two deep groove ball bearings of the 6200 size (10 mm bore); the paper names none
HUB_BEARING_BORE_M = 0.010
#: assumed: 50 mm between the hub's two bearings, which take the platform's overturning moment as a radial couple
HUB_BEARING_SPACING_M = 0.05
#: assumed: the rails and hub, about 1 kg of aluminium (rig.yaml's hub_arm_inertia), balanced about the hub axis
HUB_ARM_MASS_KG = 1.0
#: the weight the rails carry: platform, heave link and foil assembly (the mass the plant's tilt force acts on), N.
#: The foil's buoyancy (about 1 N for a 0.3 x 0.06 m section 5.5 mm thick on average) is left out: its material,
#: and so its net weight in water, is not known
PLATFORM_ASSEMBLY_WEIGHT_N = GRAVITY_M_S2 * (_RIG.platform_mass_kg + _RIG.heave_link_mass_kg
                                             + _RIG.foil_assembly_mass_kg)
#: the sum of the hub bearings' loads, N: the hub's whole weight (arm and platform) as thrust on one of them, plus
#: the platform's weight at the lane radius as a couple on both, 2 W R / spacing (the arm balanced: no moment). The
#: two add as magnitudes: SKF's constant-mu estimate does not resolve axial and radial load factors
HUB_BEARING_LOAD_N = (GRAVITY_M_S2 * HUB_ARM_MASS_KG + PLATFORM_ASSEMBLY_WEIGHT_N
                      + 2.0 * PLATFORM_ASSEMBLY_WEIGHT_N * _RIG.constrained_lane_radius_m / HUB_BEARING_SPACING_M)
#: Schaeffler (INA) linear ball bearings KN..-B, KS, KB on shafts, unsealed: 0.001-0.0025 (the upper end: grease,
#: not oil); profile rail ball carriages 0.002-0.003 (Thomson, THK). The platform runs on linear ball bushings on
#: a pair of round rails (paper Sec. 2: "a set of linear bearings"). Seals would add 2-5 N per bushing whatever the
#: load (NB Corporation, Frictional resistance and required thrust); the paper does not say the bushings are sealed
LINEAR_BALL_BUSHING_FRICTION = 0.0025
#: linear ball bushings: static and dynamic friction differ marginally (NB Corporation, same page)
LINEAR_BUSHING_BREAKAWAY_RATIO = 1.0

# --- the foil's drag ---------------------------------------------------------------------------------------------
#: Hoerner, Fluid-Dynamic Drag (1965), Ch. 3: a rectangular flat plate broadside to the flow, aspect ratio about 5
#: (the foil's 0.3 m span over its 0.06 m chord): C_D about 1.2 (1.17 square, 1.98 two-dimensional)
FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT = 1.2
#: assumed: skin friction of a thin section, per planform area (the paper's pipeline and the separation drag)
THIN_SECTION_AXIAL_DRAG_COEFFICIENT = 0.01
#: assumed: the foil's speed through the water, the middle of the 0.1-0.3 m/s of the paper's maneuvers, m/s
FOIL_REFERENCE_SPEED_M_S = 0.2

# --- surface waves -----------------------------------------------------------------------------------------------
#: assumed: ripples of 1 mm amplitude, which the foil's own flapping raises in a 1.75 m tank (the paper saw "many
#: surface waves" at lambda = 1.2, Sec. 7.1)
WAVE_AMPLITUDE_M = 0.001
#: assumed: the waves' frequency, of the order of the foil's flapping, Hz
WAVE_FREQUENCY_HZ = 1.0
#: thin aerofoil theory's lift slope, per rad: the foil's normal force per angle of attack the waves' velocity makes
THIN_AEROFOIL_LIFT_SLOPE_PER_RAD = 2.0 * math.pi


def wave_angle_of_attack_rad() -> float:
    """The angle of attack the waves' orbital velocity makes at the foil's mid-span.

    u / v_ref with u = a omega exp(-k z), deep-water waves (k = omega^2 / g), z half the foil's span below the
    surface; a = WAVE_AMPLITUDE_M, omega = 2 pi WAVE_FREQUENCY_HZ, v_ref = FOIL_REFERENCE_SPEED_M_S.

    Returns
    -------
    float
        The angle of attack, rad.
    """
    omega_rad_s = 2.0 * math.pi * WAVE_FREQUENCY_HZ
    wavenumber_per_m = omega_rad_s ** 2 / GRAVITY_M_S2
    orbital_speed_m_s = WAVE_AMPLITUDE_M * omega_rad_s * math.exp(-wavenumber_per_m * 0.5 * _RIG.foil_span_m)
    return orbital_speed_m_s / FOIL_REFERENCE_SPEED_M_S


@dataclasses.dataclass(frozen=True)
class Disturbances:
    """Sizes of the disturbances; zero switches one off.

    The defaults are physical (module docstring; each with its source in docs/disturbances.md, "The sizes");
    ``paper()`` gives the ideal-flow pipeline's. How the plant applies them: docs/disturbances.md, "How the plant
    applies them".

    Attributes
    ----------
    hub_viscous_n_m_s : float
        Viscous friction b of the hub (alpha), N m s (per rad).
    hub_coulomb_n_m : float
        Coulomb (sliding) friction torque of the hub, N m.
    hub_static_n_m : float
        Static (breakaway) friction limit of the hub, N m, >= hub_coulomb_n_m.
    rail_viscous_n_s_m : float
        Viscous friction b of the rails (R, free vehicle only), N s/m.
    rail_coulomb_n : float
        Coulomb friction force of the rails, N.
    rail_static_n : float
        Static friction limit of the rails, N, >= rail_coulomb_n.
    foil_normal_drag_coefficient : float
        Cd of the quadratic drag on the foil's normal velocity V (foil frame, eq. 40), per planform area chord x
        span, dimensionless.
    foil_axial_drag_coefficient : float
        Cd of the quadratic drag on the foil's chordwise velocity U, per planform area, dimensionless.
    platform_drag_area_m2 : float
        Cd A of the parts that move in water with the platform (tangential R alphadot, radial Rdot), m^2.
    tilt_rad : float
        The platform's tilt from level, rad: gravity's in-plane component m g sin(tilt) acts on the platform
        assembly.
    tilt_direction_rad : float
        The tilt's downhill direction beta in the tank frame, rad (any finite angle).
    wave_force_per_speed2_n_s2_m2 : float
        Standard deviation of the surface waves' normal force on the foil per foil speed squared, N s^2/m^2.
    wave_bandwidth_hz : float
        Corner frequency of the first-order filter of the waves' noise, Hz.
    """

    # rolling bearings: their friction is load-dependent (Coulomb, below); the speed-dependent lubricant drag at a
    # hub's < 1 rad/s and a platform's < 0.1 m/s is left out, and the water's drag is the drag terms below
    hub_viscous_n_m_s: float = 0.0
    hub_coulomb_n_m: float = DEEP_GROOVE_BALL_BEARING_FRICTION * HUB_BEARING_LOAD_N * 0.5 * HUB_BEARING_BORE_M
    hub_static_n_m: float = ROLLING_BEARING_BREAKAWAY_RATIO * hub_coulomb_n_m
    rail_viscous_n_s_m: float = 0.0
    rail_coulomb_n: float = LINEAR_BALL_BUSHING_FRICTION * PLATFORM_ASSEMBLY_WEIGHT_N
    rail_static_n: float = LINEAR_BUSHING_BREAKAWAY_RATIO * rail_coulomb_n
    # the flat plate's separation drag: what the vortex wake (attached shedding) leaves out
    foil_normal_drag_coefficient: float = FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT
    # zero-lift profile drag of the section (laminar skin friction on both sides times a thickness form factor,
    # swim_model.flow) at the reference speed, per planform area chord x span
    foil_axial_drag_coefficient: float = laminar_profile_drag_coefficient(
        FOIL_REFERENCE_SPEED_M_S * _RIG.foil_chord_m / KINEMATIC_VISCOSITY_WATER_M2_S,
        _RIG.foil_max_thickness_m / _RIG.foil_chord_m)
    # assumed: Cd d L of the foil's shaft between the surface and the foil: a circular cylinder broadside (Cd 1.0 at
    # Reynolds numbers 1e3-1e4, Hoerner Ch. 3), 10 mm across and 50 mm wet
    platform_drag_area_m2: float = 1.0 * 0.010 * 0.050
    # a platform levelled to 0.1 degree: a builder's spirit level reads 0.5-1.0 mm/m (0.029-0.057 degree), and the
    # level is set on the rails at a few places, not over the whole plane the platform sweeps
    tilt_rad: float = math.radians(0.1)
    tilt_direction_rad: float = 0.0            # assumed: the tilt's downhill direction in the tank frame
    # the normal-force std per (m/s)^2: 1/2 rho A lift slope x the waves' angle of attack at the reference speed
    wave_force_per_speed2_n_s2_m2: float = (0.5 * _RIG.water_density_kg_m3 * _RIG.foil_chord_m * _RIG.foil_span_m
                                            * THIN_AEROFOIL_LIFT_SLOPE_PER_RAD * wave_angle_of_attack_rad())
    # assumed: the filter's corner passes the 1 Hz ripples and the lowest sloshing modes of a 1.75 m circular tank
    # (0.7-1.1 Hz: omega^2 = g j'/r with j' = 1.84, 3.05, 3.83)
    wave_bandwidth_hz: float = 2.0

    def validate(self) -> None:
        """Check every size.

        Raises
        ------
        ValueError
            Unless every size is finite and non-negative (the tilt direction: finite), and each static limit is at
            least its Coulomb level.
        """
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if field.name == "tilt_direction_rad":
                ok = math.isfinite(value)
            else:
                ok = math.isfinite(value) and value >= 0.0
            if not ok:
                raise ValueError(f"disturbance {field.name} must be finite and >= 0, got {value!r}")
        if self.hub_static_n_m < self.hub_coulomb_n_m or self.rail_static_n < self.rail_coulomb_n:
            raise ValueError("a static friction limit must be at least its Coulomb level")

    @classmethod
    def none(cls) -> "Disturbances":
        """The ideal model: every disturbance off.

        Returns
        -------
        Disturbances
            Every size zero.
        """
        return cls(**{field.name: 0.0 for field in dataclasses.fields(cls)})

    @classmethod
    def paper(cls) -> "Disturbances":
        """The sizes of the paper's pipeline (ideal flow).

        The ideal-flow model the plans are made with has only added-mass thrust, far less than a real foil's lift,
        so the disturbances it can reject are small: these are the sizes under which the paper's constrained
        maneuver still tracks to centimetres (the paper's rig did, Sec. 7.1); with a flat plate's 1.2 or a
        0.1 degree tilt the vehicle loses the plan. All assumed.

        Returns
        -------
        Disturbances
            The paper pipeline's sizes (docs/disturbances.md, "The sizes", its paper column).
        """
        return cls(
            hub_viscous_n_m_s=0.002,          # a ball-bearing hub, a few mN m at 1 rad/s
            hub_coulomb_n_m=0.003,            # sliding friction torque of the hub bearing and encoder
            hub_static_n_m=0.005,             # breakaway torque, above the Coulomb level
            rail_viscous_n_s_m=0.5,           # linear bearings on the rails
            rail_coulomb_n=0.3,               # about 2 % of the platform's weight
            rail_static_n=0.5,                # breakaway force, above the Coulomb level
            foil_normal_drag_coefficient=0.05,   # shrunk, see above (a flat plate broadside: 1.2, Hoerner)
            foil_axial_drag_coefficient=THIN_SECTION_AXIAL_DRAG_COEFFICIENT,
            platform_drag_area_m2=0.0005,      # Cd A of the submerged peduncle and brackets
            tilt_rad=0.0002,                   # a platform level to about 0.01 degree
            tilt_direction_rad=0.0,            # the tilt's downhill direction in the tank frame
            wave_force_per_speed2_n_s2_m2=0.05,  # std of the wave force on the foil per (m/s)^2
            wave_bandwidth_hz=2.0)             # surface waves of a 1.75 m tank, up to ~2 Hz

    @classmethod
    def separation_drag(cls) -> "Disturbances":
        """Every disturbance off but the foil's quadratic drag.

        A flat plate broadside normal to the chord and a thin section's skin friction along it: the separated flow
        the attached vortex wake lacks (swim_model.wake_coupling).

        Returns
        -------
        Disturbances
            FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT normal and THIN_SECTION_AXIAL_DRAG_COEFFICIENT axial, the rest
            zero.
        """
        return dataclasses.replace(cls.none(), foil_normal_drag_coefficient=FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT,
                                   foil_axial_drag_coefficient=THIN_SECTION_AXIAL_DRAG_COEFFICIENT)

    def coulomb_and_static(self, constrained: bool) -> list[tuple[int, float, float]]:
        """(coordinate index, Coulomb level, static limit) of each coordinate with dry friction.

        Parameters
        ----------
        constrained : bool
            Whether the rails are locked (q = (alpha, phi, theta)): then the hub alone has dry friction.

        Returns
        -------
        list of (int, float, float)
            Index into q (0 the hub, 1 the rails), Coulomb level and static limit (N m for the hub, N for the
            rails); a coordinate whose static limit is zero is left out.
        """
        pairs = [(0, self.hub_coulomb_n_m, self.hub_static_n_m)]
        if not constrained:
            pairs.append((1, self.rail_coulomb_n, self.rail_static_n))
        return [p for p in pairs if p[2] > 0.0]
