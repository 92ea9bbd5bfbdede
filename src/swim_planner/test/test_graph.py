"""The state-transition graph of the shipped library, and goal search."""
import pytest

from swim_planner.errors import ManeuverError
from swim_planner.graph import build_graph, plan_to_goal
from swim_planner.maneuver import concatenate


@pytest.fixture(scope="module")
def graph(library):
    return build_graph(library)


def test_graph_of_figs_9_and_12(graph):
    """Fig. 9: rest and two cruises; Fig. 12: two lanes x two energies, with rests."""
    assert graph.mismatches == [] and graph.pruned == []
    assert {n for n in graph.nodes if n.startswith("constrained")} == {
        "constrained/rest", "constrained/cruise/E0.05", "constrained/cruise/E0.10"}
    assert len([n for n in graph.nodes if n.startswith("free/cruise")]) == 4
    assert len([n for n in graph.nodes if n.startswith("free/rest")]) == 2
    lane_changes = [e for e in graph.edges if "lane_change" in e.primitive_id]
    assert {(e.source, e.target) for e in lane_changes} >= {("free/cruise/R0.43/E0.05", "free/cruise/R0.48/E0.05")}


def test_goal_distance_is_covered_and_the_plan_connects(graph, library, rig):
    sequence = plan_to_goal(graph, "constrained/rest", "constrained/rest", min_advance_rad=4.0)
    plan = concatenate(library, rig, sequence)  # raises if a junction did not match
    assert plan.q[-1, 0] - plan.q[0, 0] >= 4.0
    assert sequence[0][0].startswith("constrained/accelerate") and sequence[-1][0].startswith("constrained/decelerate")


def test_lane_change_goal(graph, library, rig):
    sequence = plan_to_goal(graph, "free/rest/R0.43", "free/rest/R0.48")
    assert any("lane_change/R0.43-R0.48" in pid for pid, _ in sequence)
    plan = concatenate(library, rig, sequence)
    assert plan.q[-1, 1] == pytest.approx(0.48, abs=1e-6)


def test_a_goal_that_is_the_start_needs_a_distance(graph):
    with pytest.raises(ManeuverError, match="the start is the goal 'free/rest/R0.43': ask for a distance"):
        plan_to_goal(graph, "free/rest/R0.43", "free/rest/R0.43")
    sequence = plan_to_goal(graph, "free/rest/R0.43", "free/rest/R0.43", min_advance_rad=0.5)
    assert sequence[0][0].startswith("free/accelerate/R0.43") and sequence[-1][0].startswith("free/decelerate/R0.43")


def test_unreachable_and_unknown_goals(graph):
    with pytest.raises(ManeuverError, match="unknown goal state"):
        plan_to_goal(graph, "constrained/rest", "constrained/cruise/E0.20")
    with pytest.raises(ManeuverError, match="no sequence of primitives"):
        plan_to_goal(graph, "constrained/rest", "free/rest/R0.48")


def test_the_summary_lists_every_primitive_with_its_states_energies_and_advance(graph, library):
    """Each primitive's summary against what its id and stored motion say: an accelerate goes from rest to the
    cruise of its energy, a cruise-to-cruise between the two energies of its id, the advance is alpha's change."""
    import dataclasses
    import re

    from swim_planner.graph import summarize
    summaries = summarize(library, graph)
    assert [s.primitive_id for s in summaries] == sorted(library.ids())
    energies = re.compile(r"E(\d\.\d+)")
    for summary in summaries:
        primitive = library.get(summary.primitive_id)
        assert summary.advance_rad == primitive.q[-1, 0] - primitive.q[0, 0]
        assert summary.duration_s == library.spec(summary.primitive_id).duration_s and summary.in_graph
        levels = [float(e) for e in energies.findall(summary.primitive_id)]
        expected = {"accelerate": (0.0, levels[0]), "decelerate": (levels[0], 0.0), "cruise": (levels[0],) * 2,
                    "lane_change": (levels[0],) * 2, "cruise_to_cruise": tuple(levels)}[summary.primitive_type]
        assert (summary.start_energy_j, summary.end_energy_j) == expected, summary.primitive_id
        assert summary.start_state.startswith("constrained/" if summary.constrained else "free/")
        edge = next(e for e in graph.edges if e.primitive_id == summary.primitive_id)
        assert (summary.start_state, summary.end_state) == (edge.source, edge.target)
    # a primitive the graph dropped is still listed, and says so
    dropped = dataclasses.replace(graph, edges=[e for e in graph.edges if e.primitive_id != summaries[0].primitive_id])
    assert [s.in_graph for s in summarize(library, dropped)] == [False] + [True] * (len(summaries) - 1)
