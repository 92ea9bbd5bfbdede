"""bridge_node's joint_commands fuzzed over DDS (tests/fuzz_strategies.py), on the emulated rig.

One active bridge for the module. Commands of every kind (well formed within and far past the motor limits, held
long enough to drive a link to its stops; malformed) are sent a little over a period apart; every state the
bridge publishes has finite values and efforts within the motor limits, and heave and pitch stay within their hard
limits; afterwards the node is alive, and after a reset a good command reaches the motors.

The emulated rig has the rig's hard stops at those limits (as the rig cannot, the emulated run cannot pass them
however the host stalls the real-time loop); that the bridge's braking alone keeps the links within their limits
under such commands is tested deterministically, with the stops off, in swim_hw_bridge's test_braking.py.
"""
import math
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swim_ros.testing.fixtures import running_node
from swim_ros.testing.fuzz import fuzz_settings, joint_states, to_joint_state, torques
from test_bridge_node import BAD_COMMAND_SPACING_S, HOLD_S, BridgeClient, efforts

ACTUATED = ("phi", "theta")
#: published positions are the encoders' (one heave count is 7e-5 rad; a link held at its lower stop reads up to a
#: count below it): a joint more than this past a hard limit has passed it
POSITION_TOLERANCE_RAD = 1e-3
#: how long one fuzzed command is held before the next: up to ten periods, so full torque builds speed
HOLD_PERIODS = 10
#: the bridge's overrun_limit here: its largest value, so no host load latches OVERRUN in the middle of the fuzz
NEVER_LATCHED_OVERRUNS = 10000


@pytest.fixture(scope="module")
def bridge(ros_domain, tmp_path_factory):
    import rclpy
    from lifecycle_msgs.msg import Transition
    log = tmp_path_factory.mktemp("fuzz_bridge") / "log.txt"
    # overruns never latch here: on a loaded host the loop overran three periods in a row within seconds, and the
    # zero current of the OVERRUN fault let a link swinging at full speed coast through its limit (the emulated
    # rig has no stop); this module fuzzes the command path
    with running_node("swim_hw_bridge", "bridge_node", log, "-r", "__ns:=/fuzz", "-p", "watchdog_periods:=25",
                      "-p", "diagnostics_rate_hz:=20.0", "-p", f"overrun_limit:={NEVER_LATCHED_OVERRUNS}") as process:
        context = rclpy.Context()
        rclpy.init(context=context)
        client = BridgeClient(context, "/fuzz", log)
        try:
            assert client.transition(Transition.TRANSITION_CONFIGURE)
            assert client.transition(Transition.TRANSITION_ACTIVATE)
            assert client.trigger(client.reset).success
            client.hold(HOLD_S)
            yield process, client
        finally:
            client.close()
            rclpy.shutdown(context=context)


@pytest.fixture(scope="module")
def limits():
    from swim_hw_bridge.conversions import load_bridge_config
    config = load_bridge_config()
    hard = ((config.heave_lower_hard_limit_rad, config.heave_upper_hard_limit_rad),
            (config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad))
    return np.array(config.torque_limits_n_m), hard


#: states seen during the fuzz with heave or pitch past its hard limit (asserted empty by its own test, below)
PAST_A_LIMIT: list = []


def check_states(client, limits, since):
    """Every state finite with efforts within the motor limits; states with a joint past its hard limit kept."""
    torque_limits, hard = limits
    for _, state in client.states:
        assert all(math.isfinite(v) for v in [*state.position, *state.velocity, *state.effort]), state
    for effort in efforts(client, since):
        assert np.all(np.abs(effort) <= torque_limits), effort
    tolerance = POSITION_TOLERANCE_RAD
    PAST_A_LIMIT.extend(state for _, state in client.states
                        if not all(lower - tolerance <= state.position[index] <= upper + tolerance
                                   for index, (lower, upper) in zip((2, 3), hard)))


@fuzz_settings(80)
@given(command=joint_states(ACTUATED, torques(), field="effort", with_velocity=False),
       periods=st.integers(1, HOLD_PERIODS))
def test_fuzzed_commands_never_take_torque_or_a_joint_past_its_limits(bridge, limits, command, periods):
    process, client = bridge
    client.states.clear()
    sent = time.monotonic()
    message = to_joint_state(command)
    message.header.stamp = client.node.get_clock().now().to_msg()
    client.commands.publish(message)
    client.spin(max(periods * 0.008, BAD_COMMAND_SPACING_S))
    check_states(client, limits, sent)
    assert process.poll() is None


def test_no_joint_passed_its_hard_limit_during_the_fuzz(bridge):
    assert not PAST_A_LIMIT, f"{len(PAST_A_LIMIT)} states past a hard limit, the first: {PAST_A_LIMIT[0]}"


def test_after_the_fuzz_a_reset_and_a_good_command_reach_the_motors(bridge, limits):
    process, client = bridge
    assert client.trigger(client.reset).success
    client.hold(HOLD_S)
    client.states.clear()
    client.send([0.05, 0.0])
    sent = time.monotonic()
    assert client.wait_for(lambda: (0.05, 0.0) in [pytest.approx(e) for e in efforts(client, sent)]), \
        client.log_tail()
    check_states(client, limits, sent)
    assert process.poll() is None
