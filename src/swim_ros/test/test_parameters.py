"""Parameters from one table: ranges and read_only through ParameterDescriptor, checks on set, start-up values
refused by name, accepted values applied after the set."""
import dataclasses
import functools
import math

import pytest
from rclpy.parameter import Parameter

from swim_ros.parameters import (
    NodeSettings,
    ParameterSpec,
    check_parameters,
    check_settings_type,
    declare_parameters,
    markdown_table,
    positive,
)

TABLE = (
    ParameterSpec("period_s", 0.008, "control period, s", range=(0.001, 0.1), read_only=True),
    ParameterSpec("depth", 5, "history depth", range=(1, 1000)),
    ParameterSpec("gain", 1.0, "a gain above zero", range=(0.0, 1e3), check=positive),
    ParameterSpec("path", "", "a file"),
)


@pytest.fixture()
def node(rclpy_context):
    import rclpy
    made = rclpy.create_node("parameter_table", context=rclpy_context)
    declare_parameters(made, TABLE)
    made.applied = []
    made.add_on_set_parameters_callback(functools.partial(check_parameters, TABLE))
    made.add_post_set_parameters_callback(lambda parameters: made.applied.extend(p.name for p in parameters))
    yield made
    made.destroy_node()


def test_descriptors_carry_description_range_and_read_only(node):
    period, depth, gain, path = node.describe_parameters([spec.name for spec in TABLE])
    assert period.read_only and period.description == "control period, s"
    assert (period.floating_point_range[0].from_value, period.floating_point_range[0].to_value) == (0.001, 0.1)
    assert (depth.integer_range[0].from_value, depth.integer_range[0].to_value) == (1, 1000)
    assert not gain.read_only and not path.floating_point_range and not path.integer_range


@pytest.mark.parametrize("name, value, reason", [
    ("depth", 0, "out of range"), ("depth", 1001, "out of range"), ("gain", math.nan, "out of range"),
    ("gain", 0.0, "above zero"), ("period_s", 0.01, "read-only"), ("depth", 2.5, "type"),
])
def test_a_bad_set_is_refused_with_a_reason_and_changes_nothing(node, name, value, reason):
    before = node.get_parameter(name).value
    result, = node.set_parameters([Parameter(name, value=value)])
    assert not result.successful and reason in result.reason.lower().replace("read only", "read-only")
    assert node.get_parameter(name).value == before and node.applied == []


def test_a_good_set_is_applied_after_it_is_accepted(node):
    result, = node.set_parameters([Parameter("depth", value=7)])
    assert result.successful and node.get_parameter("depth").value == 7 and node.applied == ["depth"]


@pytest.mark.parametrize("overrides, message", [
    ([Parameter("depth", value=0)], "depth"), ([Parameter("gain", value=0.0)], "gain must be above zero")])
def test_a_bad_start_up_value_names_the_parameter(rclpy_context, overrides, message):
    import rclpy
    made = rclpy.create_node("parameter_table_bad", context=rclpy_context, parameter_overrides=overrides)
    try:
        with pytest.raises(ValueError, match=message):
            declare_parameters(made, TABLE)
    finally:
        made.destroy_node()


@dataclasses.dataclass(frozen=True)
class Gains:
    low: float = 1.0
    high: float = 2.0

    def __post_init__(self) -> None:
        if self.low > self.high:
            raise ValueError(f"gains.low {self.low} is above gains.high {self.high}")


@dataclasses.dataclass(frozen=True)
class TableSettings:
    period_s: float
    depth: int
    gain: float
    path: str
    gains: Gains
    extra: dict[str, float]


GROUPED_TABLE = TABLE + (ParameterSpec("gains.low", 1.0, "lower gain"), ParameterSpec("gains.high", 2.0, "upper"),
                         ParameterSpec("extra.a", 0.5, "a"), ParameterSpec("extra.b", 0.25, "b"))


@pytest.fixture()
def settings_node(rclpy_context):
    import rclpy
    made = rclpy.create_node("parameter_settings", context=rclpy_context)
    changes = []
    settings = NodeSettings(made, GROUPED_TABLE, TableSettings,
                            on_change=lambda previous, current: changes.append((previous, current)),
                            check=lambda s: "depth must not be 7" if s.depth == 7 else None)
    yield made, settings, changes
    made.destroy_node()


def test_the_snapshot_holds_the_table_and_follows_accepted_sets(settings_node):
    node, settings, changes = settings_node
    assert settings.current == TableSettings(0.008, 5, 1.0, "", Gains(1.0, 2.0), {"a": 0.5, "b": 0.25})
    first = settings.current
    result = node.set_parameters_atomically([Parameter("depth", value=8), Parameter("gains.high", value=3.0),
                                             Parameter("extra.b", value=0.75)])
    assert result.successful
    assert settings.current == dataclasses.replace(first, depth=8, gains=Gains(1.0, 3.0), extra={"a": 0.5, "b": 0.75})
    assert changes == [(first, settings.current)]


@pytest.mark.parametrize("parameters, reason", [
    ([Parameter("gains.low", value=5.0)], "gains.low 5.0 is above gains.high 2.0"),   # the group's own check
    ([Parameter("depth", value=7)], "depth must not be 7"),                            # the node's check
    ([Parameter("gain", value=0.0)], "parameter gain must be above zero"),             # the table's check
])
def test_a_set_the_snapshot_refuses_changes_nothing(settings_node, parameters, reason):
    node, settings, changes = settings_node
    before = settings.current
    result = node.set_parameters_atomically(parameters)
    assert not result.successful and reason in result.reason
    assert settings.current == before and changes == []
    assert [node.get_parameter(name).value for name in ("gains.low", "depth", "gain")] == [1.0, 5, 1.0]


@pytest.mark.parametrize("fields, message", [
    ({"period_s": float, "depth": int, "gain": float}, r"missing \['path'\]"),
    ({"period_s": float, "depth": int, "gain": float, "path": str, "speed": float}, r"not parameters \['speed'\]"),
    ({"period_s": float, "depth": float, "gain": float, "path": str}, "depth is float"),
])
def test_a_settings_type_that_does_not_match_its_table_is_refused(fields, message):
    settings_type = dataclasses.make_dataclass("Wrong", list(fields.items()), frozen=True)
    with pytest.raises(TypeError, match=message):
        check_settings_type(settings_type, TABLE)


def test_the_markdown_table_has_a_row_per_parameter_with_its_facts():
    rows = markdown_table(TABLE).splitlines()
    assert len(rows) == 2 + len(TABLE)
    assert rows[2] == "| `period_s` | `0.008` | [0.001, 0.1] | no | control period, s |"
    assert rows[5] == '| `path` | `""` |  | yes | a file |'
