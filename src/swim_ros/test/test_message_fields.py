"""Fields from YAML as ros2cli sets them (swim_ros.testing.message_fields), on real message types."""
import array

import pytest

from swim_ros.testing.message_fields import message_from_yaml


def test_scalars_arrays_and_strings_take_their_fields_types():
    from swim_interfaces.action import PerformManeuver
    goal = message_from_yaml(PerformManeuver.Goal, "{mode: 1, goal_state: free/rest/R0.48, goal_alpha_rad: 6, "
                                                   "primitive_ids: [a, b], repeat_counts: [1, 14]}")
    assert (goal.mode, goal.goal_state, goal.primitive_ids) == (1, "free/rest/R0.48", ["a", "b"])
    assert type(goal.goal_alpha_rad) is float and goal.goal_alpha_rad == 6.0    # an int typed as a float64's
    assert isinstance(goal.repeat_counts, array.array) and goal.repeat_counts.typecode == "I"
    assert list(goal.repeat_counts) == [1, 14]
    assert goal.time_scale == 0.0 and goal.goal_tolerance_r_m == 0.0              # the rest at their defaults


def test_nested_messages_and_sequences_of_messages():
    from sensor_msgs.msg import JointState
    from swim_interfaces.srv import ListPrimitives
    state = message_from_yaml(JointState, "{header: {stamp: {sec: 3, nanosec: 5}, frame_id: f}, name: [alpha], "
                                          "position: [0.5]}")
    assert (state.header.stamp.sec, state.header.stamp.nanosec, state.header.frame_id) == (3, 5, "f")
    listing = message_from_yaml(ListPrimitives.Response, "{primitives: [{primitive_id: p, duration_s: 3}, "
                                                         "{in_graph: true}]}")
    assert [type(p).__name__ for p in listing.primitives] == ["PrimitiveInfo"] * 2
    assert (listing.primitives[0].primitive_id, listing.primitives[0].duration_s, listing.primitives[1].in_graph) \
        == ("p", 3.0, True)


@pytest.mark.parametrize("text, error", [("{no_such_field: 1}", AttributeError),
                                         ("{mode: text}", ValueError), ("[1, 2]", TypeError)])
def test_what_ros2cli_refuses_is_refused(text, error):
    from swim_interfaces.action import PerformManeuver
    with pytest.raises(error):
        message_from_yaml(PerformManeuver.Goal, text)
