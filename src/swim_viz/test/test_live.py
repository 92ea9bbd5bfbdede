"""swim_viz.live without ROS: the stream bounds, the maneuver call's checks, the fault log lines and the scene
entities, each entity decoded back by the protobuf schema Foxglove reads it with."""
import json
import math

import pytest
from foxglove.messages import SceneUpdate

from swim_ros.testing.foxglove_client import decode_protobuf
from swim_viz.live import (
    CLOCKWISE_RGBA,
    COUNTER_CLOCKWISE_RGBA,
    VORTEX_DIAMETER_RANGE_M,
    VORTEX_FULL_SCALE_CIRCULATION_M2_S,
    LogLine,
    ManeuverRequestError,
    RateGate,
    fault_changes,
    parse_maneuver_request,
    path_entity,
    wake_entity,
)


def test_a_rate_gate_lets_through_one_message_per_interval_and_drops_the_rest():
    gate = RateGate(10.0)
    times_s = [k * 0.01 for k in range(100)]   # 100 Hz for 1 s
    passed = [t for t in times_s if gate.due(t)]
    assert len(passed) == 10 and gate.dropped == 90
    assert all(b - a >= 0.1 - 1e-12 for a, b in zip(passed, passed[1:]))
    unbounded = RateGate(0.0)
    assert all(unbounded.due(t) for t in times_s)
    for bad in (-1.0, math.nan, math.inf):
        with pytest.raises(ValueError):
            RateGate(bad)


def test_a_sequence_and_a_goal_become_the_action_goal_fields():
    sequence = parse_maneuver_request(json.dumps({
        "mode": "sequence", "primitive_ids": ["free/accelerate/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
        "repeat_counts": [1, 2], "time_scale": 1.5, "goal_tolerance_alpha_rad": 0.25}).encode())
    assert sequence == {"mode": 0, "primitive_ids": ["free/accelerate/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
                        "repeat_counts": [1, 2], "time_scale": 1.5, "path_tolerance_alpha_rad": 0.0,
                        "path_tolerance_r_m": 0.0, "goal_tolerance_alpha_rad": 0.25, "goal_tolerance_r_m": 0.0}
    goal = parse_maneuver_request(b'{"mode": "goal", "goal_state": "free/rest/R0.48", "goal_alpha_rad": -6.3}')
    assert goal["mode"] == 1 and goal["goal_state"] == "free/rest/R0.48" and goal["goal_alpha_rad"] == -6.3


@pytest.mark.parametrize("payload, reason", [
    (b"\xff\xfe", "not JSON"),
    (b"{", "not JSON"),
    (b"[]", "a JSON object"),
    (b'{"mode": "sequence", "primitive_ids": ["a"], "speed": 2}', "unknown fields \\['speed'\\]"),
    (b'{"primitive_ids": ["a"]}', "mode must be one of"),
    (b'{"mode": "sequence"}', "needs primitive_ids"),
    (b'{"mode": "sequence", "primitive_ids": []}', "needs primitive_ids"),
    (b'{"mode": "sequence", "primitive_ids": ["a", 3]}', "needs primitive_ids"),
    (b'{"mode": "sequence", "primitive_ids": ["a"], "repeat_counts": [0]}', "integers >= 1"),
    (b'{"mode": "sequence", "primitive_ids": ["a"], "repeat_counts": [true]}', "integers >= 1"),
    (b'{"mode": "sequence", "primitive_ids": ["a", "b"], "repeat_counts": [1]}', "1 repeat_counts for 2"),
    (b'{"mode": "goal"}', "needs goal_state"),
    (b'{"mode": "goal", "goal_state": "x", "goal_alpha_rad": "far"}', "goal_alpha_rad must be a finite number"),
    (b'{"mode": "goal", "goal_state": "x", "goal_alpha_rad": NaN}', "goal_alpha_rad must be a finite number"),
    (b'{"mode": "goal", "goal_state": "x", "time_scale": -1}', "time_scale must be at least 0"),
    (b'{"mode": "goal", "goal_state": "x", "path_tolerance_r_m": Infinity}', "path_tolerance_r_m must be a finite"),
])
def test_a_malformed_maneuver_call_is_refused_with_what_is_wrong(payload, reason):
    with pytest.raises(ManeuverRequestError, match=reason):
        parse_maneuver_request(payload)


def test_faults_latched_and_cleared_become_log_lines():
    assert fault_changes("NONE", "NONE") == []
    assert fault_changes("NONE", "OVERRUN|EMERGENCY_STOP") == [
        LogLine("error", "bridge: EMERGENCY_STOP latched, motors off"),
        LogLine("error", "bridge: OVERRUN latched, motors off")]
    assert fault_changes("OVERRUN", "OVERRUN|HARD_LIMIT", source="bridge_node") == [
        LogLine("error", "bridge_node: HARD_LIMIT latched, motors off")]
    assert fault_changes("OVERRUN|HARD_LIMIT", "NONE") == [
        LogLine("info", "bridge: faults cleared (HARD_LIMIT|OVERRUN)")]


def decoded_scene(*entities) -> object:
    update = SceneUpdate(entities=list(entities))
    schema = SceneUpdate.get_schema()
    return decode_protobuf(schema.name, schema.data, update.encode())


def test_a_path_is_one_line_strip_with_its_points_colour_width_and_stamp():
    points_m = [[0.43, 0.0, 0.0], [0.42, 0.05, 0.0], [0.40, 0.10, 0.01]]
    scene = decoded_scene(path_entity("planned_foil/0", "tank", points_m, (0.2, 0.6, 1.0, 1.0), 0.004,
                                      1_700_000_000_123_456_789))
    (entity,) = scene.entities
    assert entity.id == "planned_foil/0" and entity.frame_id == "tank"
    assert (entity.timestamp.seconds, entity.timestamp.nanos) == (1_700_000_000, 123_456_789)
    (line,) = entity.lines
    assert [(p.x, p.y, p.z) for p in line.points] == [tuple(p) for p in points_m]
    assert line.thickness == 0.004 and (line.color.r, line.color.g, line.color.b, line.color.a) == (0.2, 0.6, 1.0, 1.0)


def test_the_wake_is_a_sphere_per_vortex_sized_by_its_strength_coloured_by_its_sign():
    x_m, y_m = [0.1, 0.2, 0.3, 0.4], [0.5, 0.6, 0.7, 0.8]
    circulations_m2_s = [0.0, 0.5 * VORTEX_FULL_SCALE_CIRCULATION_M2_S, -4 * VORTEX_FULL_SCALE_CIRCULATION_M2_S,
                         math.nan]
    (entity,) = decoded_scene(wake_entity("wake", "tank", x_m, y_m, circulations_m2_s, 5)).entities
    small, large = VORTEX_DIAMETER_RANGE_M
    assert len(entity.spheres) == 3   # the non-finite vortex is left out
    assert [(s.pose.position.x, s.pose.position.y) for s in entity.spheres] == list(zip(x_m[:3], y_m[:3]))
    assert [s.size.x for s in entity.spheres] == pytest.approx([small, (small + large) / 2, large])
    colours = [c for s in entity.spheres for c in (s.color.r, s.color.g, s.color.b, s.color.a)]
    assert colours == pytest.approx([*COUNTER_CLOCKWISE_RGBA, *COUNTER_CLOCKWISE_RGBA, *CLOCKWISE_RGBA])
    with pytest.raises(ValueError, match="differ in length"):
        wake_entity("wake", "tank", [0.0], [0.0, 1.0], [0.0], 0)
