"""sim_node fuzzed over DDS (swim_ros.testing.fuzz): joint_commands, set_state and reset, parameter sets.

One node for the module (lock-step, constrained). For every example: an answer within its deadline, a malformed
or out-of-bounds one refused with a reason and changing nothing, nothing published non-finite, torque within the
motor limits and heave and pitch within their hard stops; afterwards the node is alive and steps on a good
command.
"""
import math
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_sim_node import POLICY, RESEND_AFTER_S, Driver, running_sim

from swim_ros.testing.fixtures import new_rclpy_context
from swim_ros.testing.fuzz import (
    EDGE_FLOATS,
    NON_FINITE,
    any_float,
    fuzz_parameter_sets,
    fuzz_settings,
    in_order,
    joint_states,
    to_joint_state,
    torques,
)

SEED = 5
ACTUATED = ("phi", "theta")
JOINTS = ("alpha", "phi", "theta")
#: a service answer or a step: milliseconds here; 5 s for a loaded 2-core host
DEADLINE_S = 5.0
#: published positions are measured: quantized (one count, 1.2e-4 rad for pitch) after noise of 0.3 counts; eight
#: pitch counts above a hard stop is measurement, not a joint past it
MEASURED_POSITION_TOLERANCE_RAD = 1e-3


@pytest.fixture(scope="module")
def sim(ros_domain, tmp_path_factory):
    log = tmp_path_factory.mktemp("fuzz_sim_node") / "log.txt"
    with running_sim(log, "-p", f"seed:={SEED}") as process:
        yield process


@pytest.fixture(scope="module")
def driver(sim, ros_domain):
    with new_rclpy_context() as context, Driver(context) as driver:
        driver.reset_and_wait()
        yield driver


@pytest.fixture(scope="module")
def set_state(driver):
    """set_state's client, discovered outside the deadlines: an answer sent before the client's reader matched is
    lost, and asked again 10 s later (swim_ros.calls); a request naming no joints is refused and changes nothing."""
    from swim_interfaces.srv import SetVehicleState

    from swim_ros.calls import call_service
    client = driver.node.create_client(SetVehicleState, "set_state")
    assert not call_service(driver.executor, client, SetVehicleState.Request(), POLICY).success
    return client


@pytest.fixture(scope="module")
def limits():
    """(torque limits, hard limits, set_state's bounds) from the rig file's limits, not from the node."""
    from swim_control.trajectory import MAX_ABS_START_ALPHA_RAD
    from swim_model import load_rig
    rig = load_rig()
    hard = {"phi": rig.hard_limits_rad[0], "theta": rig.hard_limits_rad[1]}
    alpha = MAX_ABS_START_ALPHA_RAD
    speeds = {"alpha": rig.limits.hub_max_speed_rad_s, "phi": rig.limits.heave.max_speed_rad_s,
              "theta": rig.limits.pitch.max_speed_rad_s}
    return np.array(rig.torque_limits_n_m), hard, {"alpha": (-alpha, alpha), **hard}, speeds


def check_published(state, limits):
    """What every published state must be: finite, efforts within the motor limits, joints within the stops."""
    torque_limits, hard, _, _ = limits
    assert all(math.isfinite(v) for v in [*state.position, *state.velocity, *state.effort]), state
    assert np.all(np.abs(state.effort[-2:]) <= torque_limits), state.effort
    for joint in ACTUATED:
        lower, upper = hard[joint]
        position = state.position[list(state.name).index(joint)]
        assert lower - MEASURED_POSITION_TOLERANCE_RAD <= position <= upper + MEASURED_POSITION_TOLERANCE_RAD


def next_state(driver, stamp):
    """The first state published after the one stamped stamp (a resend of that one skipped)."""
    start = time.monotonic()
    assert driver.wait_for_states(1)
    done = lambda: any(s.header.stamp != stamp for s in driver.states)  # noqa: E731
    assert spin_until_done(driver, done), "no state within the deadline"
    assert time.monotonic() - start < DEADLINE_S
    return next(s for s in driver.states if s.header.stamp != stamp)


def spin_until_done(driver, done):
    from swim_ros.calls import spin_until
    return spin_until(driver.executor, done, DEADLINE_S)


@fuzz_settings(80)
@given(command=joint_states(ACTUATED, torques(), field="effort", with_velocity=False),
       sentinel=st.tuples(st.floats(-2.0, 2.0), st.floats(-1.0, 1.0)))
def test_fuzzed_commands_step_only_when_well_formed_within_the_limits(sim, driver, limits, command, sentinel):
    torque_limits = limits[0]
    stamp = driver.states[-1].header.stamp
    driver.states.clear()
    driver.publisher.publish(to_joint_state(command, stamp))
    if command.defect is None:
        expected = np.clip(in_order(command, ACTUATED, command.effort), -torque_limits, torque_limits)
    else:   # the bad one must not step: the good one after it, for the same state, does
        driver.command(stamp, sentinel)
        expected = np.clip(sentinel, -torque_limits, torque_limits)
    state = next_state(driver, stamp)
    assert list(state.effort[-2:]) == list(expected), (command, state.effort)
    check_published(state, limits)
    assert sim.poll() is None


def positions():
    """Positions: inside the stops, exactly at them (accepted), just past them (refused), absurd and malformed."""
    at_stops = (1.0471975511965976, 1.3962634015954636)   # 60 and 80 degrees: the rig file's hard stops
    just_past = tuple(math.nextafter(v, math.inf) for v in at_stops)
    borderline = at_stops + just_past
    return st.one_of(st.floats(-1.5, 1.5), st.sampled_from(borderline + tuple(-v for v in borderline)),
                     st.sampled_from((1e6, -1e6, 2e6, *EDGE_FLOATS, *NON_FINITE)), any_float())


def speeds():
    """Velocities: within and past the physically possible joint speeds (3, 30, 45 rad/s), absurd, malformed."""
    return st.one_of(st.floats(-50.0, 50.0), st.sampled_from((3.0, -45.0, 45.0, 30.0, 45.5, 1e300)), any_float())


def within_bounds(request, limits):
    """Whether a well-formed set_state request is within the simulator's documented bounds."""
    _, _, position_bounds, speed_bounds = limits
    q = dict(zip(request.name, request.position))
    qdot = dict(zip(request.name, request.velocity or [0.0] * len(request.name)))
    return all(position_bounds[j][0] <= q[j] <= position_bounds[j][1] and abs(qdot[j]) <= speed_bounds[j]
               for j in JOINTS)


@fuzz_settings(80)
@given(request=joint_states(JOINTS, positions(), velocity_value=speeds()), reset_after=st.booleans())
def test_fuzzed_set_state_is_refused_with_a_reason_or_puts_the_vehicle_there(sim, driver, set_state, limits, request,
                                                                            reset_after):
    from std_srvs.srv import Trigger
    from swim_interfaces.srv import SetVehicleState

    from swim_ros.calls import call_service
    accepted = request.defect is None and within_bounds(request, limits)
    driver.states.clear()
    start = time.monotonic()
    reply = call_service(driver.executor, set_state, SetVehicleState.Request(state=to_joint_state(request)), POLICY)
    assert time.monotonic() - start < DEADLINE_S
    assert reply.success == accepted, (request, reply.message)
    if accepted:
        assert spin_until_done(driver, lambda: bool(driver.states))
        state = driver.states[-1]
        check_published(state, limits)
        measured = dict(zip(state.name, state.position))
        for joint in JOINTS:
            target = request.position[request.name.index(joint)]
            assert abs(measured[joint] - target) <= MEASURED_POSITION_TOLERANCE_RAD * max(1.0, abs(target) * 1e-6)
    else:
        assert reply.message
    if reset_after:
        assert driver.call(Trigger, "reset", Trigger.Request()).success
    assert sim.poll() is None


def test_parameter_sets_are_answered_refused_with_a_reason_or_applied(sim, driver, limits):
    from swim_ros.calls import ParameterCalls
    from swim_sim.sim_node import PARAMETERS
    parameters = ParameterCalls(driver.node, driver.executor, "sim_node", POLICY)
    # afterwards the module's other tests run with the defaults (the resend delay: the test's own)
    fuzz_parameter_sets(parameters, PARAMETERS, 60, DEADLINE_S, lambda: sim.poll() is None,
                        {"resend_after_s": RESEND_AFTER_S})
    # still serving: a reset answers and a good command steps
    from std_srvs.srv import Trigger
    driver.states.clear()
    assert driver.call(Trigger, "reset", Trigger.Request()).success
    assert spin_until_done(driver, lambda: bool(driver.states))
    stamp = driver.states[-1].header.stamp
    driver.command(stamp, (0.1, 0.0))
    state = next_state(driver, stamp)
    assert list(state.effort[-2:]) == [0.1, 0.0]
    check_published(state, limits)
