"""Parameters from one table: ranges and read_only through ParameterDescriptor, checks on set, start-up values
refused by name, accepted values applied after the set."""
import functools
import math

import pytest
from rclpy.parameter import Parameter

from swim_ros.parameters import ParameterSpec, check_parameters, declare_parameters, positive

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
