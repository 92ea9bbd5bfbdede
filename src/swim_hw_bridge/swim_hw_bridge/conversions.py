"""Bridge parameters (config/bridge.yaml: the device) and the conversions between device units and joint units.

The bridge file holds the device: quadrature decoding, motor constants, amplifiers, DAC, home pose. The encoders'
lines, the gear ratios and the joints' limits (stops, soft margins, speeds, torque limits) are the rig's
(swim_model's rig file, RigParameters and its limits record), which a BridgeConfig carries with it.

Encoders (paper Sec. 2; lines from the rig), with x4 quadrature decoding (c = 4 counts per line, an assumed entry):
    hub:   alpha = alpha_0 + n_hub * 2 pi / (c * 6144)               rad
    rail:  R     = R_0     + n_rail / (c * 1024 / 0.0254 m)          m
    heave: phi   = phi_0   + n_heave * 2 pi / (c * 512 * 43)         rad   (512 lines on the motor, 43:1 gear)
    pitch: theta = theta_0 + n_pitch * 2 pi / (c * 512 * 25)         rad   (512 lines on the motor, 25:1 gear)
with n the unwrapped count since the device was opened (unwrap.py) and the home pose (alpha_0, R_0, phi_0,
theta_0) where the rig stands at start-up (incremental encoders).

Motors in current (torque) mode (Sec. 2): joint torque tau = N Kt i, so i = tau / (N Kt), with N the gear ratio
and Kt the motor's torque constant (assumed datasheet values; gearhead losses ignored). Amplifier command
voltage (mf624 backend): v = i / g with g the amplifier's transconductance in A/V (assumed).

Every value is a named entry of the YAML file with its unit and either its paper section or why it is assumed.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from swim_model import RigParameters, load_rig
from swim_model.units import POSITIVE, SIGNED, UNITS, EntryError, entry_to_si

FORMAT_VERSION = 1

#: dimensions of the bridge file: swim_model's units plus the electrical and frequency units the bridge needs
BRIDGE_UNITS: dict[str, dict[str, float]] = {
    **UNITS,
    "current": {"A": 1.0, "mA": 1e-3},
    "voltage": {"V": 1.0},
    "transconductance": {"A/V": 1.0},
    "torque_constant": {"N*m/A": 1.0, "mN*m/A": 1e-3},
    "frequency": {"Hz": 1.0},
}
_SUFFIX = {"ratio": "", "torque_constant": "n_m_per_a", "current": "a", "voltage": "v", "transconductance": "a_per_v",
           "angle": "rad", "length": "m", "frequency": "hz"}

#: the (heave, pitch) motors' and amplifiers' entries, "<joint>_<what>": what -> dimension (each positive)
_PER_MOTOR: dict[str, str] = {
    "torque_constant": "torque_constant", "current_limit": "current", "amplifier_gain": "transconductance",
}
#: the home pose's entries, "<coordinate>_home_position": coordinate -> dimension (each signed)
_HOME_POSITIONS: dict[str, str] = {"hub": "angle", "rail": "length", "heave": "angle", "pitch": "angle"}
#: parameter key -> (dimension, sign rule)
_SCHEMA: dict[str, tuple[str, str]] = {
    "quadrature_counts_per_line": ("ratio", POSITIVE),
    **{f"{joint}_{what}": (dimension, POSITIVE)
       for what, dimension in _PER_MOTOR.items() for joint in ("heave", "pitch")},
    "dac_range": ("voltage", POSITIVE),
    **{f"{coordinate}_home_position": (dimension, SIGNED) for coordinate, dimension in _HOME_POSITIONS.items()},
    "velocity_cutoff": ("frequency", POSITIVE),
}


class BridgeConfigError(ValueError):
    """The bridge parameter file is missing an entry, names a wrong unit, or holds an impossible value."""


def _field_name(key: str) -> str:
    suffix = _SUFFIX[_SCHEMA[key][0]]
    return f"{key}_{suffix}" if suffix else key


@dataclasses.dataclass(frozen=True)
class BridgeConfig:
    """The bridge's parameters in SI units (field names carry the unit), and the rig they drive."""

    quadrature_counts_per_line: float
    heave_torque_constant_n_m_per_a: float
    pitch_torque_constant_n_m_per_a: float
    heave_current_limit_a: float
    pitch_current_limit_a: float
    heave_amplifier_gain_a_per_v: float
    pitch_amplifier_gain_a_per_v: float
    dac_range_v: float
    hub_home_position_rad: float
    rail_home_position_m: float
    heave_home_position_rad: float
    pitch_home_position_rad: float
    velocity_cutoff_hz: float
    rig: RigParameters   # the rig's encoder lines, gear ratios and joint limits
    source_path: str = dataclasses.field(default="", compare=False)
    #: backend name -> its own settings (port, device paths, emulation options), from the file's backend_options
    backend_options: Mapping[str, Mapping[str, Any]] = dataclasses.field(default_factory=dict, compare=False)

    def as_dict(self) -> dict[str, Any]:
        """Field name -> SI value, plus rig and source_path (no backend options)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "backend_options"}

    def device_config(self, backend: str) -> dict[str, Any]:
        """The dict a backend is constructed with: the SI values plus that backend's options."""
        return {**self.as_dict(), **dict(self.backend_options.get(backend, {}))}

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> "BridgeConfig":
        """The config back from a device_config() dict (extra keys ignored)."""
        names = {f.name for f in dataclasses.fields(cls)} - {"backend_options"}
        return cls(**{name: values[name] for name in names if name in values})

    @property
    def counts_per_unit(self) -> tuple[float, float, float, float]:
        """Counts per joint unit (hub, rail, heave, pitch): per rad, per m, per rad, per rad."""
        c, rig = self.quadrature_counts_per_line, self.rig
        two_pi = 2.0 * math.pi
        return (c * rig.hub_encoder_lines_per_rev / two_pi,
                c * rig.rail_encoder_lines_per_m,
                c * rig.heave_encoder_lines_per_rev * rig.heave_gear_ratio / two_pi,
                c * rig.pitch_encoder_lines_per_rev * rig.pitch_gear_ratio / two_pi)

    @property
    def home_positions(self) -> tuple[float, float, float, float]:
        """(alpha rad, R m, phi rad, theta rad) at start-up, where the unwrapped counts are zero."""
        return (self.hub_home_position_rad, self.rail_home_position_m, self.heave_home_position_rad,
                self.pitch_home_position_rad)

    @property
    def motor_torque_gains_n_m_per_a(self) -> tuple[float, float]:
        """N Kt of (heave, pitch): joint torque per ampere, N m/A."""
        return (self.rig.heave_gear_ratio * self.heave_torque_constant_n_m_per_a,
                self.rig.pitch_gear_ratio * self.pitch_torque_constant_n_m_per_a)

    @property
    def current_limits_a(self) -> tuple[float, float]:
        """The (heave, pitch) current limits, A."""
        return (self.heave_current_limit_a, self.pitch_current_limit_a)


def default_config_path() -> Path:
    """The bridge file shipped with the package."""
    return Path(str(resources.files("swim_hw_bridge") / "config" / "bridge.yaml"))


def load_bridge_config(path: str | Path | None = None, rig: RigParameters | None = None) -> BridgeConfig:
    """Read and check a bridge file for a rig.

    The shipped bridge file when path is None or empty; swim_model's shipped rig when rig is None. Raises
    BridgeConfigError.
    """
    source = Path(path) if path else default_config_path()
    try:
        document = yaml.safe_load(source.read_text())
    except (OSError, yaml.YAMLError) as err:
        raise BridgeConfigError(f"{source}: cannot read the bridge file: {err}") from err
    return config_from_mapping(document, str(source), rig)


def config_from_mapping(document: Any, origin: str = "<mapping>", rig: RigParameters | None = None) -> BridgeConfig:
    """Check a parsed bridge file and convert it to SI, for rig (None: swim_model's shipped rig)."""
    if not isinstance(document, Mapping) or document.get("format_version") != FORMAT_VERSION:
        raise BridgeConfigError(f"{origin}: expected a mapping with format_version: {FORMAT_VERSION}")
    entries = document.get("parameters")
    if not isinstance(entries, Mapping):
        raise BridgeConfigError(f"{origin}: 'parameters' must be a mapping")
    missing = sorted(set(_SCHEMA) - set(entries))
    unknown = sorted(set(entries) - set(_SCHEMA))
    if missing or unknown:
        raise BridgeConfigError(f"{origin}: missing parameters {missing}, unknown parameters {unknown}")
    values = {_field_name(key): _entry_to_si(key, entries[key], origin) for key in _SCHEMA}
    options = document.get("backend_options", {}) or {}
    if not isinstance(options, Mapping) or not all(isinstance(v, Mapping) for v in options.values()):
        raise BridgeConfigError(f"{origin}: 'backend_options' must map backend names to mappings")
    config = BridgeConfig(**values, rig=load_rig() if rig is None else rig, source_path=origin,
                          backend_options=options)
    _check_consistency(config)
    return config


def _entry_to_si(key: str, entry: Any, origin: str) -> float:
    dimension, sign_rule = _SCHEMA[key]
    try:
        return entry_to_si(entry, dimension, sign_rule, f"{origin}: parameter '{key}'", BRIDGE_UNITS)
    except EntryError as err:
        raise BridgeConfigError(str(err)) from err


def _check_consistency(config: BridgeConfig) -> None:
    where = config.source_path or "bridge config"
    for joint, (lower, upper), margin in zip(("heave", "pitch"), config.rig.hard_limits_rad,
                                             config.rig.limits.soft_margins_rad):
        home = getattr(config, f"{joint}_home_position_rad")
        if not lower + margin <= home <= upper - margin:
            raise BridgeConfigError(f"{where}: {joint}_home_position must lie inside the rig's soft limits "
                                    f"({config.rig.source_path or 'rig'})")
    full_scale_a = (config.heave_amplifier_gain_a_per_v * config.dac_range_v,
                    config.pitch_amplifier_gain_a_per_v * config.dac_range_v)
    for joint, limit_a, full_a in zip(("heave", "pitch"), config.current_limits_a, full_scale_a):
        if limit_a > full_a:
            raise BridgeConfigError(f"{where}: {joint}_current_limit {limit_a} A is beyond the amplifier's full "
                                    f"scale {full_a} A (gain * dac_range)")


class Conversions:
    """Counts <-> joint positions, joint torques <-> motor currents <-> amplifier volts, for one config."""

    def __init__(self, config: BridgeConfig) -> None:
        self.config = config
        self.units_per_count = tuple(1.0 / n for n in config.counts_per_unit)
        self.home_positions = config.home_positions
        self.torque_gains_n_m_per_a = config.motor_torque_gains_n_m_per_a

    def counts_to_positions(self, unwrapped_counts: Sequence[int]) -> tuple[float, float, float, float]:
        """(alpha rad, R m, phi rad, theta rad) from counts since open (hub, rail, heave, pitch)."""
        h, s = self.home_positions, self.units_per_count
        return (h[0] + unwrapped_counts[0] * s[0], h[1] + unwrapped_counts[1] * s[1],
                h[2] + unwrapped_counts[2] * s[2], h[3] + unwrapped_counts[3] * s[3])

    def torques_to_currents(self, heave_n_m: float, pitch_n_m: float) -> tuple[float, float]:
        """The currents i = tau / (N Kt), amperes, for (heave, pitch) joint torques in N m."""
        return (heave_n_m / self.torque_gains_n_m_per_a[0], pitch_n_m / self.torque_gains_n_m_per_a[1])

    def currents_to_torques(self, heave_a: float, pitch_a: float) -> tuple[float, float]:
        """The joint torques tau = N Kt i, N m, for (heave, pitch) currents in A."""
        return (heave_a * self.torque_gains_n_m_per_a[0], pitch_a * self.torque_gains_n_m_per_a[1])

    def currents_to_volts(self, heave_a: float, pitch_a: float) -> tuple[float, float]:
        """Amplifier command v = i / g, volts (g in A/V)."""
        return (heave_a / self.config.heave_amplifier_gain_a_per_v, pitch_a / self.config.pitch_amplifier_gain_a_per_v)
