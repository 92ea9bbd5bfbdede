"""A node's parameters from one table: declared with ParameterDescriptor ranges, checked on set, applied after.

Follows ros2/demos and rclcpp's parameter guidance: each parameter is declared once with its description, its
range (``FloatingPointRange`` / ``IntegerRange``, so ``ros2 param describe`` and rclpy itself refuse a value out of
range, NaN included) and ``read_only`` where a change at run time could not take effect (rclpy refuses setting it,
with a reason). A rule a range cannot say (a file that must load, a bound that must be positive) is a ``check``
run by the on-set callback, which only validates; the node applies accepted values in its post-set callback.

    TABLE = (ParameterSpec("sample_period_s", 0.008, "control period, s", range=(0.001, 0.1), read_only=True),
             ParameterSpec("boundary_layer", 0.05, "sliding-mode boundary layer phi", range=(0.0, 1e3),
                           check=positive))
    declare_parameters(node, TABLE)
    node.add_on_set_parameters_callback(functools.partial(check_parameters, TABLE))
    node.add_post_set_parameters_callback(node.apply_parameters)
"""
from __future__ import annotations

import dataclasses
import math
import typing
from typing import Any, Callable, Generic, Mapping, Optional, Sequence, TypeVar, Union

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.node import Node

from swim_ros.realtime import SCHEDULING_POLICIES, RealtimeSettings, parse_cpu_list

ParameterValue = Union[bool, int, float, str, list]
#: a node's settings type: a frozen dataclass with a field per parameter of its table (check_settings_type)
SettingsT = TypeVar("SettingsT")
#: a rule beyond the range: the reason a value is not valid, or None if it is
Check = Callable[[Any], Optional[str]]


@dataclasses.dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a node.

    name, default (its type is the parameter's type), what it is (with its unit), an inclusive range for numbers,
    read_only if it is fixed once the node has started, and an extra check.
    """

    name: str
    default: ParameterValue
    description: str
    range: Optional[tuple[float, float]] = None
    read_only: bool = False
    check: Optional[Check] = None

    def descriptor(self) -> ParameterDescriptor:
        """The rclpy ParameterDescriptor of this parameter: description, read-only flag and range."""
        descriptor = ParameterDescriptor(name=self.name, description=self.description, read_only=self.read_only)
        if self.range is not None:
            low, high = self.range
            if isinstance(self.default, bool) or not isinstance(self.default, (int, float)):
                raise TypeError(f"parameter {self.name}: a range needs a numeric default, got {self.default!r}")
            if isinstance(self.default, int):
                descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high), step=0)]
            else:
                descriptor.floating_point_range = [FloatingPointRange(from_value=float(low), to_value=float(high),
                                                                      step=0.0)]
        return descriptor

    def reason_invalid(self, value: Any) -> Optional[str]:
        """Why value is not valid for this parameter (range and check), or None.

        rclpy checks the range too; this also serves the values a node is started with.
        """
        if self.range is not None:
            low, high = self.range
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                return f"parameter {self.name} must be a number in [{low:g}, {high:g}], got {value!r}"
        if self.check is not None:
            reason = self.check(value)
            if reason is not None:
                return f"parameter {self.name} {reason}, got {value!r}"
        return None


def declare_parameters(node: Node, table: Sequence[ParameterSpec]) -> None:
    """Declare every parameter of table on node.

    ValueError naming the first start-up value that is not valid (rclpy's own range refusal included), so run_node
    reports it as a fatal start-up error.
    """
    from rclpy.exceptions import InvalidParameterValueException
    for spec in table:
        try:
            node.declare_parameter(spec.name, spec.default, spec.descriptor())
        except InvalidParameterValueException as err:
            raise ValueError(f"parameter {spec.name}: {err}") from err
        reason = spec.reason_invalid(node.get_parameter(spec.name).value)
        if reason is not None:
            raise ValueError(reason)


def check_parameters(table: Sequence[ParameterSpec], parameters: Sequence[Any]) -> SetParametersResult:
    """The on-set callback.

    Refuses the whole set, with the first reason, if any value is not valid. Parameters not in table (rclpy's own, such
    as use_sim_time) pass.
    """
    specs = {spec.name: spec for spec in table}
    for parameter in parameters:
        spec = specs.get(parameter.name)
        reason = spec.reason_invalid(parameter.value) if spec is not None else None
        if reason is not None:
            return SetParametersResult(successful=False, reason=reason)
    return SetParametersResult(successful=True)


def positive(value: Any) -> Optional[str]:
    """A check: the value must be above zero (a range is inclusive)."""
    return None if isinstance(value, (int, float)) and value > 0 else "must be above zero"


def finite(value: Any) -> Optional[str]:
    """A check: the value must be a finite number."""
    return None if isinstance(value, (int, float)) and math.isfinite(value) else "must be a finite number"


def one_of(*choices: str) -> Check:
    """A check: the value must be one of choices."""
    def check(value: Any) -> Optional[str]:
        return None if value in choices else f"must be one of {', '.join(repr(c) for c in choices)}"
    return check


def realtime_parameters(priority: int, thread: str) -> tuple[ParameterSpec, ...]:
    """The real-time means of a periodic node (swim_ros.realtime.RealtimeSettings), fixed at start.

    Its field priority is the default priority of thread (which of the node's threads it sets: "node's threads", ...).
    """

    def cpu_list(value: Any) -> Optional[str]:
        if value == "":
            return None
        try:
            parse_cpu_list(value)
        except (ValueError, AttributeError) as err:
            return f"must be a CPU list such as '1', '0,2' or '2-3' ({err})"
        return None

    return (
        ParameterSpec("realtime_policy", "fifo", f"scheduling policy of the {thread}: "
                      f"{' | '.join(SCHEDULING_POLICIES)} (other: no real-time means); where the host refuses it the "
                      "node warns once and runs as an ordinary process", check=one_of(*SCHEDULING_POLICIES),
                      read_only=True),
        ParameterSpec("realtime_priority", priority, f"real-time priority of the {thread} (1-98; the kernel's own "
                      "threads hold 99)", range=(1, 98), read_only=True),
        ParameterSpec("lock_memory", True, "mlockall the process's current and future pages, so no page fault "
                      "stalls a period", read_only=True),
        ParameterSpec("cpu_affinity", "", "CPUs the process runs on, taskset's list form ('1', '2-3'); empty: every "
                      "CPU (on the rig: the CPUs isolcpus keeps free)", check=cpu_list, read_only=True),
        ParameterSpec("collect_garbage_between_periods", True, "freeze the start-up's objects, turn automatic "
                      "garbage collection off and collect at a period's end once a second instead",
                      read_only=True),
    )


@dataclasses.dataclass(frozen=True)
class RealtimeParameterSettings:
    """The fields of realtime_parameters' table, for a node's settings type to derive from.

    The settings type is that of a node that declares the table (NodeSettings).
    """

    realtime_policy: str
    realtime_priority: int
    lock_memory: bool
    cpu_affinity: str
    collect_garbage_between_periods: bool

    @property
    def realtime(self) -> RealtimeSettings:
        """The real-time means these fields ask for."""
        return RealtimeSettings(self.realtime_policy, self.realtime_priority, self.lock_memory, self.cpu_affinity,
                                self.collect_garbage_between_periods)


def _field_types(settings_type: type) -> dict[str, Any]:
    params = getattr(settings_type, "__dataclass_params__", None)
    if not dataclasses.is_dataclass(settings_type) or params is None or not params.frozen:
        raise TypeError(f"{settings_type.__name__} must be a frozen dataclass")
    hints = typing.get_type_hints(settings_type)
    return {field.name: hints[field.name] for field in dataclasses.fields(settings_type)}


def _group_kind(field_type: Any) -> Optional[str]:
    """How a settings field holds the parameters named "<field>.<name>".

    "dataclass" (a field per name), "dict" (every such parameter, by name), or None (the field is one parameter).
    """
    if isinstance(field_type, type) and dataclasses.is_dataclass(field_type):
        return "dataclass"
    return "dict" if typing.get_origin(field_type) is dict else None


def check_settings_type(settings_type: type, table: Sequence[ParameterSpec]) -> None:
    """TypeError unless settings_type is a frozen dataclass holding table's parameters, each once.

    A field named as the parameter, typed as its default; or, for the parameters named "<group>.<name>", a field <group>
    that is a dataclass with a field per name, or a dict of them all.
    """
    names = [spec.name for spec in table]
    defaults = {spec.name: spec.default for spec in table}
    held: list[str] = []
    for name, field_type in _field_types(settings_type).items():
        kind = _group_kind(field_type)
        if kind == "dataclass":
            held += [f"{name}.{field.name}" for field in dataclasses.fields(field_type)]
        elif kind == "dict":
            held += [parameter for parameter in names if parameter.startswith(f"{name}.")]
        else:
            held.append(name)
            expected = typing.get_origin(field_type) or field_type
            if name in defaults and isinstance(expected, type) and not isinstance(defaults[name], expected):
                raise TypeError(f"{settings_type.__name__}.{name} is {expected.__name__}, the parameter's default "
                                f"{defaults[name]!r}")
    missing, extra = sorted(set(names) - set(held)), sorted(set(held) - set(names))
    if missing or extra or len(held) != len(set(held)):
        raise TypeError(f"{settings_type.__name__} does not hold its table's parameters: missing {missing}, "
                        f"not parameters {extra}")


def settings_from_values(settings_type: type[SettingsT], values: Mapping[str, Any]) -> SettingsT:
    """settings_type (check_settings_type) made from values, parameter name -> value.

    The groups' dataclasses check themselves (ValueError, TypeError).
    """
    arguments: dict[str, Any] = {}
    for name, field_type in _field_types(settings_type).items():
        kind = _group_kind(field_type)
        prefix = f"{name}."
        group = {key[len(prefix):]: value for key, value in values.items() if key.startswith(prefix)}
        arguments[name] = (field_type(**group) if kind == "dataclass" else group if kind == "dict"
                           else values[name])
    return settings_type(**arguments)


def read_settings(node: Node, table: Sequence[ParameterSpec], settings_type: type[SettingsT]) -> SettingsT:
    """The node's parameters of table now, as settings_type.

    ValueError with the first reason a value is not valid.
    """
    values = {spec.name: node.get_parameter(spec.name).value for spec in table}
    for spec in table:
        reason = spec.reason_invalid(values[spec.name])
        if reason is not None:
            raise ValueError(reason)
    return settings_from_values(settings_type, values)


class NodeSettings(Generic[SettingsT]):
    """A node's parameters as one frozen snapshot, the shape of ros2_controllers' generate_parameter_library.

    The table is declared on node (a start-up value that is not valid: ValueError naming it), a set is refused with the
    first reason (the table's ranges and checks, the snapshot it would make, then check on that snapshot) and changes
    nothing; once accepted, ``current`` is the new snapshot and on_change(previous, current) runs (the post-set
    callback). Hot paths read ``current``'s fields, never get_parameter.
    """

    def __init__(self, node: Node, table: Sequence[ParameterSpec], settings_type: type[SettingsT], *,
                 on_change: Optional[Callable[[SettingsT, SettingsT], None]] = None,
                 check: Optional[Callable[[SettingsT], Optional[str]]] = None) -> None:
        check_settings_type(settings_type, table)
        self._node, self._table, self._settings_type = node, tuple(table), settings_type
        self._names = frozenset(spec.name for spec in table)
        self._on_change, self._check = on_change, check
        declare_parameters(node, table)
        self.current: SettingsT = read_settings(node, table, settings_type)
        if check is not None:
            reason = check(self.current)
            if reason is not None:
                raise ValueError(reason)
        node.add_on_set_parameters_callback(self._check_set)
        node.add_post_set_parameters_callback(self._refresh)

    def _check_set(self, parameters: Sequence[Any]) -> SetParametersResult:
        result = check_parameters(self._table, parameters)
        if not result.successful:
            return result
        values = {**self._flat_values(), **{parameter.name: parameter.value for parameter in parameters}}
        try:
            candidate = settings_from_values(self._settings_type, values)
        except (ValueError, TypeError) as err:
            return SetParametersResult(successful=False, reason=str(err))
        reason = self._check(candidate) if self._check is not None else None
        return SetParametersResult(successful=reason is None, reason=reason or "")

    def _flat_values(self) -> dict[str, Any]:
        return {spec.name: self._node.get_parameter(spec.name).value for spec in self._table}

    def _refresh(self, parameters: Sequence[Any]) -> None:
        if not any(parameter.name in self._names for parameter in parameters):   # rclpy's own (use_sim_time)
            return
        previous = self.current
        self.current = settings_from_values(self._settings_type, self._flat_values())
        if self._on_change is not None:
            self._on_change(previous, self.current)


def markdown_table(table: Sequence[ParameterSpec]) -> str:
    """The parameter table as a README's markdown table: name, default, range, when it can change, what it is."""
    rows = ["| parameter | default | range | set at run time | what |", "|---|---|---|---|---|"]
    for spec in table:
        default = "true" if spec.default is True else "false" if spec.default is False else \
            '""' if spec.default == "" else f"{spec.default!r}" if isinstance(spec.default, list) else f"{spec.default}"
        bounds = f"[{spec.range[0]:g}, {spec.range[1]:g}]" if spec.range is not None else ""
        description = spec.description.replace("|", "\\|")
        rows.append(f"| `{spec.name}` | `{default}` | {bounds} | {'no' if spec.read_only else 'yes'} | "
                    f"{description} |")
    return "\n".join(rows) + "\n"
