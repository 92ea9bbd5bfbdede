"""Rig parameters: loading, validation and the typed record the models read.

The rig file (``config/rig.yaml`` in this package by default) holds one entry per parameter with a
value, a unit, and either the paper section it comes from (``source``) or the reason it was
assumed (``assumed``), and a ``limits`` section of the same entries, the joints' limits (swim_model.limits). Loading
converts every value to SI, and refuses a missing or unknown key, a
unit of the wrong dimension, an entry that is neither sourced nor assumed, and an impossible value
(a negative mass, a thickness not smaller than the chord, ...), each with a message naming the key.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import yaml

from swim_model.errors import RigConfigError
from swim_model.limits import HardLimits, JointLimits, RigLimits
from swim_model.units import NON_NEGATIVE, POSITIVE, SIGNED, EntryError, entry_to_si

RIG_FORMAT_VERSION = 1

# key in the file -> (dimension, sign rule); the record's field is the key plus an SI suffix.
_POSITIVE, _NONNEGATIVE, _SIGNED = POSITIVE, NON_NEGATIVE, SIGNED
_SCHEMA: dict[str, tuple[str, str]] = {
    "foil_chord": ("length", _POSITIVE),
    "foil_max_thickness": ("length", _POSITIVE),
    "foil_span": ("length", _POSITIVE),
    "water_density": ("density", _POSITIVE),
    "heave_link_length": ("length", _POSITIVE),
    "heave_pivot_inset": ("length", _SIGNED),
    "pitch_axis_to_foil_reference": ("length", _SIGNED),
    "tank_diameter": ("length", _POSITIVE),
    "constrained_lane_radius": ("length", _POSITIVE),
    "lane_1_radius": ("length", _POSITIVE),
    "lane_2_radius": ("length", _POSITIVE),
    "hub_arm_inertia": ("inertia", _NONNEGATIVE),
    "platform_mass": ("mass", _POSITIVE),
    "platform_inertia": ("inertia", _NONNEGATIVE),
    "heave_link_mass": ("mass", _NONNEGATIVE),
    "heave_link_cg_distance": ("length", _SIGNED),
    "heave_link_inertia": ("inertia", _NONNEGATIVE),
    "foil_assembly_mass": ("mass", _NONNEGATIVE),
    "foil_assembly_cg_offset": ("length", _SIGNED),
    "foil_assembly_inertia": ("inertia", _NONNEGATIVE),
    "heave_rotor_inertia": ("inertia", _NONNEGATIVE),
    "pitch_rotor_inertia": ("inertia", _NONNEGATIVE),
    "heave_gear_ratio": ("ratio", _POSITIVE),
    "pitch_gear_ratio": ("ratio", _POSITIVE),
    "heave_encoder_lines": ("lines_per_rev", _POSITIVE),
    "pitch_encoder_lines": ("lines_per_rev", _POSITIVE),
    "hub_encoder_lines": ("lines_per_rev", _POSITIVE),
    "rail_encoder_lines": ("lines_per_length", _POSITIVE),
    "sample_period": ("time", _POSITIVE),
}
#: the limits section: key "<joint>_<what>" -> dimension (every limit is positive); JointLimits' field is <what> with
#: the dimension's SI suffix
_JOINT_LIMITS: dict[str, str] = {
    "planning_range": "angle", "soft_margin": "angle", "hard_stop": "angle", "max_speed": "angular_speed",
    "torque_limit": "torque",
}
_LIMITS_SCHEMA: dict[str, str] = {
    **{f"{joint}_{what}": dimension for joint in ("heave", "pitch") for what, dimension in _JOINT_LIMITS.items()},
    "hub_max_speed": "angular_speed",
    "rail_max_speed": "speed",
}
_SUFFIX = {
    "length": "m", "mass": "kg", "inertia": "kg_m2", "density": "kg_m3", "torque": "n_m",
    "angle": "rad", "time": "s", "ratio": "", "lines_per_rev": "per_rev",
    "lines_per_length": "per_m", "angular_speed": "rad_s", "speed": "m_s",
}


def _field_name(key: str) -> str:
    suffix = _SUFFIX[_SCHEMA[key][0]]
    return f"{key}_{suffix}" if suffix else key


@dataclasses.dataclass(frozen=True)
class RigParameters:
    """The rig's parameters in SI units (field names carry the unit).

    Each value's source in the paper, or why it was assumed, is beside its key in ``config/rig.yaml``. Symbols of
    the paper: ``heave_link_length_m`` is Lh, ``heave_pivot_inset_m`` is Ld and ``pitch_axis_to_foil_reference_m``
    is Lf of eq. 40.

    Attributes
    ----------
    foil_chord_m, foil_max_thickness_m, foil_span_m : float
        The foil's chord, largest thickness and submerged span, m (Sec. 2).
    water_density_kg_m3 : float
        Water density, kg/m^3.
    heave_link_length_m : float
        Lh, heave axis to pitch axis, m.
    heave_pivot_inset_m : float
        Ld, signed, from the platform's centre of mass in to the heave axis, m.
    pitch_axis_to_foil_reference_m : float
        Lf, signed, from the pitch axis along the chord to the foil frame's origin, m.
    tank_diameter_m : float
        The tank's diameter, m.
    constrained_lane_radius_m, lane_1_radius_m, lane_2_radius_m : float
        R of the laterally constrained vehicle and of the paper's two lanes, m.
    hub_arm_inertia_kg_m2 : float
        Hub, rails and hub encoder about the hub axis, kg m^2.
    platform_mass_kg, platform_inertia_kg_m2 : float
        The platform with both motors: mass, kg, and inertia about its centre of mass, kg m^2.
    heave_link_mass_kg, heave_link_cg_distance_m, heave_link_inertia_kg_m2 : float
        The heave link: mass, kg; centre of mass from the heave axis, m; inertia about it, kg m^2.
    foil_assembly_mass_kg, foil_assembly_cg_offset_m, foil_assembly_inertia_kg_m2 : float
        Foil, pitch shaft and pulley: mass, kg; centre of mass along the chord from the pitch axis, m; inertia
        about it, kg m^2.
    heave_rotor_inertia_kg_m2, pitch_rotor_inertia_kg_m2 : float
        Motor rotor inertias, kg m^2.
    heave_gear_ratio, pitch_gear_ratio : float
        Gear ratios N, motor turns per joint turn.
    limits : RigLimits
        The joints' limits, the file's ``limits`` section (swim_model.limits): planning ranges, soft margins, hard
        stops, largest speeds and torque limits; ``heave_torque_limit_n_m``, ``pitch_torque_limit_n_m``,
        ``torque_limits_n_m`` and ``hard_limits_rad`` read it.
    heave_encoder_lines_per_rev, pitch_encoder_lines_per_rev, hub_encoder_lines_per_rev : float
        Encoder lines per motor (or hub) revolution.
    rail_encoder_lines_per_m : float
        Rail encoder lines per metre.
    sample_period_s : float
        The rig's control sample period, s.
    source_path : str
        The file the values came from ("" when built in code); not compared.
    """

    foil_chord_m: float
    foil_max_thickness_m: float
    foil_span_m: float
    water_density_kg_m3: float
    heave_link_length_m: float
    heave_pivot_inset_m: float
    pitch_axis_to_foil_reference_m: float
    tank_diameter_m: float
    constrained_lane_radius_m: float
    lane_1_radius_m: float
    lane_2_radius_m: float
    hub_arm_inertia_kg_m2: float
    platform_mass_kg: float
    platform_inertia_kg_m2: float
    heave_link_mass_kg: float
    heave_link_cg_distance_m: float
    heave_link_inertia_kg_m2: float
    foil_assembly_mass_kg: float
    foil_assembly_cg_offset_m: float
    foil_assembly_inertia_kg_m2: float
    heave_rotor_inertia_kg_m2: float
    pitch_rotor_inertia_kg_m2: float
    heave_gear_ratio: float
    pitch_gear_ratio: float
    heave_encoder_lines_per_rev: float
    pitch_encoder_lines_per_rev: float
    hub_encoder_lines_per_rev: float
    rail_encoder_lines_per_m: float
    sample_period_s: float
    limits: RigLimits   # the file's limits section: ranges, stops, speeds and torque limits of the joints
    source_path: str = dataclasses.field(default="", compare=False)

    @property
    def heave_torque_limit_n_m(self) -> float:
        """The heave joint's torque limit, N m (Sec. 2)."""
        return self.limits.heave.torque_limit_n_m

    @property
    def pitch_torque_limit_n_m(self) -> float:
        """The pitch joint's torque limit, N m (Sec. 2)."""
        return self.limits.pitch.torque_limit_n_m

    @property
    def torque_limits_n_m(self) -> tuple[float, float]:
        """(heave, pitch) joint torque limits, N m (Sec. 2)."""
        return self.limits.torque_limits_n_m

    @property
    def hard_limits_rad(self) -> HardLimits:
        """((heave lower, upper), (pitch lower, upper)): the joints' hard stops, rad."""
        return self.limits.hard_limits_rad

    def replace(self, **changes: Any) -> "RigParameters":
        """A copy with some values (or the limits record) changed, validated like a loaded file.

        Parameters
        ----------
        **changes : float or RigLimits
            New values by field name, SI (``limits``: a RigLimits).

        Returns
        -------
        RigParameters
            The changed copy.

        Raises
        ------
        RigConfigError
            When the changed values are inconsistent (a thickness not below the chord, a lane outside the tank, a
            non-finite value).
        TypeError
            For a name that is no field.
        """
        changed = dataclasses.replace(self, **changes)   # dataclasses.replace checks the names when it runs
        _check_consistency(changed)
        return changed

    def as_dict(self) -> dict[str, float]:
        """The SI values by field name, the torque limits the primitives are solved against among them.

        Returns
        -------
        dict of str to float
            Field name to value (no source path, no limits but the two torque limits).
        """
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                  if f.name not in ("source_path", "limits")}
        return {**values, "heave_torque_limit_n_m": self.heave_torque_limit_n_m,
                "pitch_torque_limit_n_m": self.pitch_torque_limit_n_m}

    def digest(self) -> str:
        """SHA-256 of the SI values: primitive libraries record it to detect a different rig.

        Returns
        -------
        str
            Hex digest.
        """
        canonical = json.dumps({k: repr(v) for k, v in sorted(self.as_dict().items())}, sort_keys=True)
        return hashlib.sha256(canonical.encode()).hexdigest()


def default_rig_path() -> Path:
    """The rig file shipped with swim_model.

    Returns
    -------
    pathlib.Path
        ``swim_model/config/rig.yaml`` in the installed package.
    """
    return Path(str(resources.files("swim_model") / "config" / "rig.yaml"))


def load_rig(path: str | Path | None = None) -> RigParameters:
    """Load and validate a rig file.

    Parameters
    ----------
    path : str or pathlib.Path, optional
        The rig file (default: the shipped ``config/rig.yaml``).

    Returns
    -------
    RigParameters
        The values in SI.

    Raises
    ------
    RigConfigError
        The file is missing or unreadable, or an entry is missing, unknown, in a unit of the wrong dimension,
        without ``source``/``assumed``, or impossible.
    """
    rig_path = Path(path) if path is not None else default_rig_path()
    try:
        document = yaml.safe_load(rig_path.read_text())
    except OSError as err:
        raise RigConfigError(f"cannot read rig file {rig_path}: {err.strerror}") from err
    except yaml.YAMLError as err:
        raise RigConfigError(f"rig file {rig_path} is not valid YAML: {err}") from err
    return rig_from_mapping(document, origin=str(rig_path))


def rig_from_mapping(document: Any, origin: str = "<mapping>") -> RigParameters:
    """Validate a parsed rig document (the YAML's structure) and convert it to SI.

    Parameters
    ----------
    document : mapping
        ``{"format_version": 1, "parameters": {key: entry}}``, each entry as ``units.entry_to_si`` reads it.
    origin : str, optional
        Where the document came from, for messages and ``source_path``.

    Returns
    -------
    RigParameters
        The document's values in SI, with ``source_path`` the origin.

    Raises
    ------
    RigConfigError
        For a wrong format version, or a missing, unknown, badly unitted, unsourced or impossible entry.
    """
    if not isinstance(document, Mapping):
        raise RigConfigError(f"{origin}: expected a mapping with 'format_version' and 'parameters'")
    if document.get("format_version") != RIG_FORMAT_VERSION:
        raise RigConfigError(
            f"{origin}: format_version is {document.get('format_version')!r}; this swim_model reads "
            f"format_version {RIG_FORMAT_VERSION}")
    entries = document.get("parameters")
    if not isinstance(entries, Mapping):
        raise RigConfigError(f"{origin}: 'parameters' must be a mapping of parameter entries")
    _check_keys(entries, _SCHEMA, "parameters", origin)
    values = {_field_name(key): _entry_to_si(key, entries[key], origin, *_SCHEMA[key]) for key in _SCHEMA}
    rig = RigParameters(**values, limits=_limits_from_mapping(document.get("limits"), origin), source_path=origin)
    _check_consistency(rig)
    return rig


def _check_keys(entries: Mapping[str, Any], schema: Mapping[str, Any], section: str, origin: str) -> None:
    missing = sorted(set(schema) - set(entries))
    unknown = sorted(set(entries) - set(schema))
    if missing:
        raise RigConfigError(f"{origin}: missing {section}: {', '.join(missing)}")
    if unknown:
        raise RigConfigError(f"{origin}: unknown {section}: {', '.join(unknown)} (misspelt?)")


def _limits_from_mapping(entries: Any, origin: str) -> RigLimits:
    """The limits section in SI, checked (RigLimits: a soft margin inside the gap between range and stop)."""
    if not isinstance(entries, Mapping):
        raise RigConfigError(f"{origin}: 'limits' must be a mapping of limit entries")
    _check_keys(entries, _LIMITS_SCHEMA, "limits", origin)
    values = {key: _entry_to_si(key, entries[key], origin, dimension, _POSITIVE)
              for key, dimension in _LIMITS_SCHEMA.items()}

    def joint(name: str) -> JointLimits:
        return JointLimits(**{f"{what}_{_SUFFIX[dimension]}": values[f"{name}_{what}"]
                              for what, dimension in _JOINT_LIMITS.items()})

    try:
        return RigLimits(joint("heave"), joint("pitch"), values["hub_max_speed"], values["rail_max_speed"])
    except RigConfigError as err:
        raise RigConfigError(f"{origin}: limits: {err}") from err


def _entry_to_si(key: str, entry: Any, origin: str, dimension: str, sign_rule: str) -> float:
    try:
        return entry_to_si(entry, dimension, sign_rule, f"{origin}: parameter '{key}'")
    except EntryError as err:
        raise RigConfigError(str(err)) from err


def _check_consistency(rig: RigParameters) -> None:
    """Relations between parameters that single entries cannot check."""
    where = rig.source_path or "rig"
    if rig.foil_max_thickness_m >= rig.foil_chord_m:
        raise RigConfigError(f"{where}: foil_max_thickness must be smaller than foil_chord")
    tank_radius_m = rig.tank_diameter_m / 2.0
    for name in ("constrained_lane_radius_m", "lane_1_radius_m", "lane_2_radius_m"):
        if getattr(rig, name) >= tank_radius_m:
            raise RigConfigError(f"{where}: {name} must lie inside the tank (radius {tank_radius_m} m)")
    for name, value in rig.as_dict().items():
        if not math.isfinite(value):
            raise RigConfigError(f"{where}: {name} is not finite")
