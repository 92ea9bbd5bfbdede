"""Bridge parameters (config/bridge.yaml) and the conversions between device units and joint units.

Encoders (paper Sec. 2), with x4 quadrature decoding (c = 4 counts per line, an assumed entry):
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
from swim_model.units import POSITIVE, SIGNED, UNITS, EntryError, entry_to_si
from swim_model.limits import HardLimits

FORMAT_VERSION = 1

#: dimensions of the bridge file: swim_model's units plus the electrical and rate units the bridge needs
BRIDGE_UNITS: dict[str, dict[str, float]] = {
    **UNITS,
    "current": {"A": 1.0, "mA": 1e-3},
    "voltage": {"V": 1.0},
    "transconductance": {"A/V": 1.0},
    "torque_constant": {"N*m/A": 1.0, "mN*m/A": 1e-3},
    "angular_speed": {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0},
    "speed": {"m/s": 1.0},
    "frequency": {"Hz": 1.0},
}
_SUFFIX = {"ratio": "", "lines_per_rev": "per_rev", "lines_per_length": "per_m", "torque": "n_m",
           "torque_constant": "n_m_per_a", "current": "a", "voltage": "v", "transconductance": "a_per_v",
           "angle": "rad", "length": "m", "angular_speed": "rad_s", "speed": "m_s", "frequency": "hz"}

_POSITIVE, _ANY = POSITIVE, SIGNED
#: parameter key -> (dimension, sign rule)
_SCHEMA: dict[str, tuple[str, str]] = {
    "quadrature_counts_per_line": ("ratio", _POSITIVE),
    "hub_encoder_lines": ("lines_per_rev", _POSITIVE),
    "rail_encoder_lines": ("lines_per_length", _POSITIVE),
    "heave_encoder_lines": ("lines_per_rev", _POSITIVE),
    "pitch_encoder_lines": ("lines_per_rev", _POSITIVE),
    "heave_gear_ratio": ("ratio", _POSITIVE),
    "pitch_gear_ratio": ("ratio", _POSITIVE),
    "heave_torque_limit": ("torque", _POSITIVE),
    "pitch_torque_limit": ("torque", _POSITIVE),
    "heave_torque_constant": ("torque_constant", _POSITIVE),
    "pitch_torque_constant": ("torque_constant", _POSITIVE),
    "heave_current_limit": ("current", _POSITIVE),
    "pitch_current_limit": ("current", _POSITIVE),
    "heave_amplifier_gain": ("transconductance", _POSITIVE),
    "pitch_amplifier_gain": ("transconductance", _POSITIVE),
    "dac_range": ("voltage", _POSITIVE),
    "heave_lower_hard_limit": ("angle", _ANY),
    "heave_upper_hard_limit": ("angle", _ANY),
    "pitch_lower_hard_limit": ("angle", _ANY),
    "pitch_upper_hard_limit": ("angle", _ANY),
    "heave_soft_limit_margin": ("angle", _POSITIVE),
    "pitch_soft_limit_margin": ("angle", _POSITIVE),
    "hub_max_speed": ("angular_speed", _POSITIVE),
    "rail_max_speed": ("speed", _POSITIVE),
    "heave_max_speed": ("angular_speed", _POSITIVE),
    "pitch_max_speed": ("angular_speed", _POSITIVE),
    "hub_home_position": ("angle", _ANY),
    "rail_home_position": ("length", _ANY),
    "heave_home_position": ("angle", _ANY),
    "pitch_home_position": ("angle", _ANY),
    "velocity_cutoff": ("frequency", _POSITIVE),
}


class BridgeConfigError(ValueError):
    """The bridge parameter file is missing an entry, names a wrong unit, or holds an impossible value."""


def _field_name(key: str) -> str:
    suffix = _SUFFIX[_SCHEMA[key][0]]
    return f"{key}_{suffix}" if suffix else key


@dataclasses.dataclass(frozen=True)
class BridgeConfig:
    """The bridge's parameters in SI units (field names carry the unit)."""

    quadrature_counts_per_line: float
    hub_encoder_lines_per_rev: float
    rail_encoder_lines_per_m: float
    heave_encoder_lines_per_rev: float
    pitch_encoder_lines_per_rev: float
    heave_gear_ratio: float
    pitch_gear_ratio: float
    heave_torque_limit_n_m: float
    pitch_torque_limit_n_m: float
    heave_torque_constant_n_m_per_a: float
    pitch_torque_constant_n_m_per_a: float
    heave_current_limit_a: float
    pitch_current_limit_a: float
    heave_amplifier_gain_a_per_v: float
    pitch_amplifier_gain_a_per_v: float
    dac_range_v: float
    heave_lower_hard_limit_rad: float
    heave_upper_hard_limit_rad: float
    pitch_lower_hard_limit_rad: float
    pitch_upper_hard_limit_rad: float
    heave_soft_limit_margin_rad: float
    pitch_soft_limit_margin_rad: float
    hub_max_speed_rad_s: float
    rail_max_speed_m_s: float
    heave_max_speed_rad_s: float
    pitch_max_speed_rad_s: float
    hub_home_position_rad: float
    rail_home_position_m: float
    heave_home_position_rad: float
    pitch_home_position_rad: float
    velocity_cutoff_hz: float
    source_path: str = dataclasses.field(default="", compare=False)
    #: backend name -> its own settings (port, device paths, emulation options), from the file's backend_options
    backend_options: Mapping[str, Mapping[str, Any]] = dataclasses.field(default_factory=dict, compare=False)

    def as_dict(self) -> dict[str, Any]:
        """Field name -> SI value, plus source_path (no backend options)."""
        values = dataclasses.asdict(self)
        del values["backend_options"]
        return values

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
        c = self.quadrature_counts_per_line
        two_pi = 2.0 * math.pi
        return (c * self.hub_encoder_lines_per_rev / two_pi,
                c * self.rail_encoder_lines_per_m,
                c * self.heave_encoder_lines_per_rev * self.heave_gear_ratio / two_pi,
                c * self.pitch_encoder_lines_per_rev * self.pitch_gear_ratio / two_pi)

    @property
    def home_positions(self) -> tuple[float, float, float, float]:
        """(alpha rad, R m, phi rad, theta rad) at start-up, where the unwrapped counts are zero."""
        return (self.hub_home_position_rad, self.rail_home_position_m, self.heave_home_position_rad,
                self.pitch_home_position_rad)

    @property
    def max_speeds(self) -> tuple[float, float, float, float]:
        """Physically possible joint speeds (rad/s, m/s, rad/s, rad/s); faster counter steps are jumps."""
        return (self.hub_max_speed_rad_s, self.rail_max_speed_m_s, self.heave_max_speed_rad_s,
                self.pitch_max_speed_rad_s)

    @property
    def motor_torque_gains_n_m_per_a(self) -> tuple[float, float]:
        """N Kt of (heave, pitch): joint torque per ampere, N m/A."""
        return (self.heave_gear_ratio * self.heave_torque_constant_n_m_per_a,
                self.pitch_gear_ratio * self.pitch_torque_constant_n_m_per_a)

    @property
    def torque_limits_n_m(self) -> tuple[float, float]:
        return (self.heave_torque_limit_n_m, self.pitch_torque_limit_n_m)

    @property
    def hard_limits_rad(self) -> HardLimits:
        """((heave lower, upper), (pitch lower, upper)): where the rig's stops hold the joints, rad."""
        return ((self.heave_lower_hard_limit_rad, self.heave_upper_hard_limit_rad),
                (self.pitch_lower_hard_limit_rad, self.pitch_upper_hard_limit_rad))

    @property
    def current_limits_a(self) -> tuple[float, float]:
        return (self.heave_current_limit_a, self.pitch_current_limit_a)


def default_config_path() -> Path:
    """The bridge file shipped with the package."""
    return Path(str(resources.files("swim_hw_bridge") / "config" / "bridge.yaml"))


def load_bridge_config(path: str | Path | None = None) -> BridgeConfig:
    """Read and check a bridge file (the shipped one when path is None or empty). Raises BridgeConfigError."""
    source = Path(path) if path else default_config_path()
    try:
        document = yaml.safe_load(source.read_text())
    except (OSError, yaml.YAMLError) as err:
        raise BridgeConfigError(f"{source}: cannot read the bridge file: {err}") from err
    return config_from_mapping(document, str(source))


def load_bridge_config_parameter(path: str) -> BridgeConfig:
    """load_bridge_config for a node's ``bridge_config_path`` parameter (empty: the shipped file). A file that does
    not load is a ValueError naming the parameter: a start-up error (swim_ros.entry.run_node)."""
    try:
        return load_bridge_config(path or None)
    except BridgeConfigError as err:
        raise ValueError(f"parameter bridge_config_path: {err}") from err


def config_from_mapping(document: Any, origin: str = "<mapping>") -> BridgeConfig:
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
    config = BridgeConfig(**values, source_path=origin, backend_options=options)
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
    for joint in ("heave", "pitch"):
        lower = getattr(config, f"{joint}_lower_hard_limit_rad")
        upper = getattr(config, f"{joint}_upper_hard_limit_rad")
        margin = getattr(config, f"{joint}_soft_limit_margin_rad")
        home = getattr(config, f"{joint}_home_position_rad")
        if not lower + 2.0 * margin < upper:
            raise BridgeConfigError(f"{where}: {joint} hard limits must be more than two soft margins apart")
        if not lower + margin <= home <= upper - margin:
            raise BridgeConfigError(f"{where}: {joint}_home_position must lie inside the soft limits")
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
        """i = tau / (N Kt), amperes, for (heave, pitch) joint torques in N m."""
        return (heave_n_m / self.torque_gains_n_m_per_a[0], pitch_n_m / self.torque_gains_n_m_per_a[1])

    def currents_to_torques(self, heave_a: float, pitch_a: float) -> tuple[float, float]:
        """tau = N Kt i, N m."""
        return (heave_a * self.torque_gains_n_m_per_a[0], pitch_a * self.torque_gains_n_m_per_a[1])

    def currents_to_volts(self, heave_a: float, pitch_a: float) -> tuple[float, float]:
        """Amplifier command v = i / g, volts (g in A/V)."""
        return (heave_a / self.config.heave_amplifier_gain_a_per_v, pitch_a / self.config.pitch_amplifier_gain_a_per_v)
