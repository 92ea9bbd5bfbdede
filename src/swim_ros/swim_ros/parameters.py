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
from typing import Any, Callable, Optional, Sequence, Union

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.node import Node

from swim_ros.realtime import SCHEDULING_POLICIES, RealtimeSettings, parse_cpu_list

ParameterValue = Union[bool, int, float, str, list]
#: a rule beyond the range: the reason a value is not valid, or None if it is
Check = Callable[[Any], Optional[str]]


@dataclasses.dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a node: name, default (its type is the parameter's type), what it is (with its unit),
    an inclusive range for numbers, read_only if it is fixed once the node has started, and an extra check."""

    name: str
    default: ParameterValue
    description: str
    range: Optional[tuple[float, float]] = None
    read_only: bool = False
    check: Optional[Check] = None

    def descriptor(self) -> ParameterDescriptor:
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
        """Why value is not valid for this parameter (range and check), or None. rclpy checks the range too;
        this also serves the values a node is started with."""
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
    """Declare every parameter of table on node; ValueError naming the first start-up value that is not valid
    (rclpy's own range refusal included), so run_node reports it as a fatal start-up error."""
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
    """The on-set callback: refuses the whole set, with the first reason, if any value is not valid. Parameters
    not in table (rclpy's own, such as use_sim_time) pass."""
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
    """The real-time means of a periodic node (swim_ros.realtime.RealtimeSettings), fixed at start; priority is
    the default priority of thread (which of the node's threads it sets: "node's threads", ...)."""

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


def realtime_settings(node: Node) -> RealtimeSettings:
    """The node's real-time parameters (declared from realtime_parameters) as RealtimeSettings."""
    get = node.get_parameter
    return RealtimeSettings(get("realtime_policy").value, get("realtime_priority").value, get("lock_memory").value,
                            get("cpu_affinity").value, get("collect_garbage_between_periods").value)
