"""planner_node fuzzed over DDS (swim_ros.testing.fuzz): request_maneuver and parameter sets.

One node for the module. For every request: an answer within its deadline; a refusal with a reason and no plan;
a plan only with finite values; afterwards the node is alive and plans the paper's maneuver.
"""
import math
import time

import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from swim_interfaces.srv import RequestManeuver
from test_planner_node import PAPER, POLICY

from swim_ros.testing.fixtures import new_rclpy_context, running_node
from swim_ros.testing.fuzz import any_float, fuzz_parameter_sets, fuzz_settings, unicode_name

#: the longest answer: a plan at the node's own bounds (7200 s of plan, about 7 s to build on a quiet host, and
#: the fuzzed counts stay far below it) or a refusal (milliseconds); 20 s for a loaded 2-core host
DEADLINE_S = 20.0
#: the planner's answers are refusals within a second (the issue's requirement for the bounded requests)
REFUSAL_DEADLINE_S = 5.0
#: an unknown id repeated 2**32 - 1 times: refused before its repeats are expanded (they would fill the memory)
UNKNOWN_REPEATED = RequestManeuver.Request(mode=RequestManeuver.Request.MODE_SEQUENCE, primitive_ids=["no/such"],
                                           repeat_counts=[2**32 - 1], time_scale=1.0,
                                           request_id="fuzz-unknown-id-repeated")
GOAL_STATES = ("constrained/rest", "free/rest/R0.43", "free/cruise/R0.48/E0.10", "constrained/cruise/E0.05")


@pytest.fixture(scope="module")
def planner(ros_domain, tmp_path_factory):
    with running_node("swim_planner", "planner_node", tmp_path_factory.mktemp("fuzz_planner") / "log.txt") as process:
        yield process


@pytest.fixture(scope="module")
def client(planner, ros_domain):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import call_service
    with new_rclpy_context() as context:
        node = rclpy.create_node("planner_fuzz_client", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        service = node.create_client(RequestManeuver, "request_maneuver")
        # discovery, outside the deadlines: an answer sent before the client's reader matched is lost, and asked
        # again 10 s later (swim_ros.calls); a refused empty request plans nothing
        call_service(executor, service, RequestManeuver.Request(), POLICY)
        yield node, executor, service
        executor.shutdown()
        node.destroy_node()


def repeat_counts():
    """uint32 counts: 1-3 (planned), 0 (refused), and huge ones a plan bound must refuse at once."""
    return st.one_of(st.integers(0, 3), st.sampled_from((100_000, 4_000_000_000, 2 ** 32 - 1)))


def primitive_ids():
    return st.one_of(st.sampled_from(PAPER[0]), st.sampled_from(("no/such", "", "constrained/cruise/E9")),
                     unicode_name())


@st.composite
def requests(draw):
    """A RequestManeuver request built field by field: sequences (known and unknown ids, counts matching or not),
    goals (known and unknown states, any goal distance), any time scale and start alpha."""
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import new_request_id
    if draw(st.booleans()):   # a sequence: the paper's, or fuzzed ids
        ids = list(PAPER[0]) if draw(st.booleans()) else draw(st.lists(primitive_ids(), max_size=6))
        counts = draw(st.one_of(st.lists(repeat_counts(), min_size=len(ids), max_size=len(ids)),
                                st.lists(repeat_counts(), max_size=7)))
    else:
        ids, counts = [], []
    return RequestManeuver.Request(
        mode=draw(st.one_of(st.sampled_from((0, 1)), st.integers(0, 255))),
        primitive_ids=ids, repeat_counts=counts,
        start_state=draw(st.one_of(st.just(""), st.sampled_from(GOAL_STATES), unicode_name())),
        goal_state=draw(st.one_of(st.sampled_from(GOAL_STATES), unicode_name())),
        goal_alpha_rad=draw(st.one_of(st.floats(0.0, 20.0), any_float())),
        time_scale=draw(st.one_of(st.sampled_from((1.0, 1.2, 0.0, -1.0)), any_float())),
        start_alpha_rad=draw(st.one_of(st.floats(-10.0, 10.0), any_float())),
        request_id=new_request_id())


def finite_plan(plan):
    """Every float64 of the plan finite."""
    return all(math.isfinite(v) for field in ("time_from_start_s", "positions", "velocities", "foil_accelerations",
                                              "feedforward_torques", "lqr_gains", "sliding_gains")
               for v in getattr(plan, field)) and math.isfinite(plan.lane_radius_m)


@fuzz_settings(80)
@given(request=requests())
@example(request=UNKNOWN_REPEATED)
def test_fuzzed_requests_are_answered_refused_with_a_reason_or_planned_finite(planner, client, request):
    from swim_ros.calls import call_service
    _, executor, service = client
    start = time.monotonic()
    reply = call_service(executor, service, request, POLICY)
    elapsed_s = time.monotonic() - start
    assert elapsed_s < (DEADLINE_S if reply.success else REFUSAL_DEADLINE_S), (request, elapsed_s)
    if reply.success:
        assert len(reply.plan.time_from_start_s) > 0 and finite_plan(reply.plan), request
    else:
        assert reply.message and len(reply.plan.time_from_start_s) == 0, request
    if not (math.isfinite(request.start_alpha_rad) and math.isfinite(request.time_scale)):
        assert not reply.success, request   # a NaN must never become a plan
    assert planner.poll() is None


def test_parameter_sets_are_answered_refused_with_a_reason_or_applied(planner, client):
    from swim_interfaces.srv import RequestManeuver

    from swim_planner.planner_node import PARAMETERS
    from swim_ros.calls import ParameterCalls, call_service, new_request_id
    node, executor, service = client
    parameters = ParameterCalls(node, executor, "planner_node", POLICY)
    fuzz_parameter_sets(parameters, PARAMETERS, 40, REFUSAL_DEADLINE_S, lambda: planner.poll() is None)
    request = RequestManeuver.Request(primitive_ids=PAPER[0], repeat_counts=PAPER[1], time_scale=1.0,
                                      request_id=new_request_id())
    reply = call_service(executor, service, request, POLICY)
    assert reply.success and finite_plan(reply.plan), reply.message
