"""Killing one node of the closed loop mid-run (SIGKILL: no clean-up of its own) leaves the others safe.

Each case brings the loop up over DDS with swim_bringup's System (parameter files of swim_bringup/config), starts
a maneuver while a RunClient records every topic to an MCAP bag, kills one node when the plan has run 1 s, keeps
recording, and then reads the bag back with rosbags: every message written is there, log times and header
stamps never run backwards. What "safe" means for each node:
- the simulator dies: tracker_node's stale-state watchdog zeroes the torque (stale_after_periods, here 2 s)
  and the goal aborts with STATE_LOST; it keeps publishing zero commands.
- the tracker dies, on the bridge: bridge_node's command watchdog (watchdog_periods) zeroes the motor torque;
  its joint_states efforts go to 0 (but for the bridge's braking of a link that coasts toward a hard limit) and
  /diagnostics reports the watchdog EXPIRED.
- the tracker dies, on sim_node in lock-step: the simulator waits for the command of the state it published;
  simulated time stops (no torque is ever integrated again) and it resends that same state now and then.
- the planner dies mid-execution: the tracker has the whole plan and finishes it.
"""
import contextlib
import time

import numpy as np
import pytest
from conftest import MESSAGE_TIMEOUT_S
from diagnostic_msgs.msg import DiagnosticArray
from rosbags.rosbag2 import Reader

from swim_bringup.bag import RUN_TOPICS, read_messages
from swim_bringup.run_client import RunClient, header_stamp_ns
from swim_bringup.system import System, closed_loop_specs
from swim_bringup.testing import SHARED_HOST_STALE_AFTER_PERIODS, shared_host_config
from swim_model.rig import load_rig

PERIOD_S = 0.008
KILL_AT_PLAN_TIME_S = 1.0
CONSTRAINED_SHORT = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05"], [1, 1])   # 9 s
FREE_SHORT = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05"], [1, 1])            # 4 s, real time
# other builds and tests share this 2-core host: these tests are about the kill, so the tracker's stale limit and
# the bridge's overrun latch are swim_bringup.testing's shared-host values (a latch before the kill would hold the
# motors at zero from the start, and leave no torque for the watchdog to zero)
STALE_AFTER_S = SHARED_HOST_STALE_AFTER_PERIODS * PERIOD_S
#: bring-up to the plan's first tracked second: nodes and discovery take seconds on a loaded host, the second itself
#: 1 s on the bridge (real time), less in lock-step; 60 s margin
FIRST_SECOND_TIMEOUT_S = 60.0
#: the simulator killed, the goal ends STALE_AFTER_S after its last state; 10 s more for the result to arrive on a
#: loaded host
STATE_LOST_RESULT_TIMEOUT_S = STALE_AFTER_S + 10.0
#: the planner killed, the tracker finishes the 9 s plan's last 8 s: 1-2 s at 6-8x real time in lock-step (README);
#: 60 s for a loaded host
PLAN_END_TIMEOUT_S = 60.0
#: the tracker killed, states and diagnostics are looked at from this long after the kill: far beyond the bridge's
#: 40 ms command watchdog (5 periods, config/bridge.yaml) on a loaded host
WATCHDOG_SETTLE_S = 0.5


@contextlib.contextmanager
def maneuver_under_way(tmp_path, plant, maneuver, topics=RUN_TOPICS, plant_overrides=()):
    """The loop up, the maneuver requested and executing, recorded; yields (system, client, plan, result future)."""
    specs = closed_loop_specs(shared_host_config("paper", tmp_path), plant_overrides, plant=plant)
    with System(specs, tmp_path / "logs") as system, RunClient(tmp_path / "bag", topics) as client:
        client.wait_for_nodes()
        plan = client.request(*maneuver, 1.0)
        result = client.execute(plan).get_result_async()
        client.spin_until(lambda: client.last_plan_time_s >= KILL_AT_PLAN_TIME_S, FIRST_SECOND_TIMEOUT_S,
                          "tracked second")
        yield system, client, plan, result


def kill(system, executable):
    """SIGKILL the node's process group; the wall time of the kill, ns (the bag's log-time clock)."""
    node = next(n for n in system.nodes if n.spec.executable == executable)
    killed_ns = time.time_ns()
    node.kill()
    assert not node.alive()
    return killed_ns


def read_back(bag_path, written):
    """The bag read with rosbags: {topic: [(log time ns, message)]}, checked against the counts written."""
    with Reader(bag_path) as reader:
        assert {c.topic: c.msgcount for c in reader.connections} == written
    topics = {topic: [] for topic in written}
    for topic, log_ns, message in read_messages(bag_path, tuple(written)):
        topics[topic].append((log_ns, message))
    for topic, rows in topics.items():
        assert len(rows) == written[topic]
        assert np.all(np.diff([log_ns for log_ns, _ in rows]) >= 0), topic
        if rows and hasattr(rows[0][1], "header") and topic != "/plan":   # the per-period topics
            stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in rows]
            assert np.all(np.diff(stamps) >= 0), f"{topic}: header stamps run backwards"
    return topics


def stamp_ns(message):
    return message.header.stamp.sec * 10**9 + message.header.stamp.nanosec


def sampled_stamps(client, topic, message_type=None):
    """A list the client's node fills with the header stamps (ns) of topic's messages from now on: what the
    waits look at (the recorder may lag; the assertions read the bag)."""
    from sensor_msgs.msg import JointState
    stamps = [0]
    client.node.create_subscription(message_type or JointState, topic, lambda m: stamps.append(stamp_ns(m)), 1000)
    return stamps


def watchdog_zeros_recorded(client, end_plan_time_s: float, zeros: int):
    """A predicate: the recorder holds every command up to the goal's end and ``zeros`` of the watchdog's after it.

    The recorder writes each topic in the order published, but may lag a lock-step loop by hundreds of periods, so
    a count of commands recorded after the goal's end can be of the backlog. The watchdog's zeros carry the stamp
    of the last state the tracker tracked (the one at end_plan_time_s, as its tracking_state): once the latest
    recorded command is a zero with that stamp, every torque before it is in the bag; then ``zeros`` - 1 more.
    (RunClient.drain waits for the states too, which the killed simulator may have taken with it.)
    """
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    first_zero = []   # the command count when the recorder first held a watchdog's zero

    def recorded() -> bool:
        if not first_zero:
            tracking, command = client.latest_cdr.get("/tracking_state"), client.latest_cdr.get("/joint_commands")
            if tracking is None or command is None or client.last_plan_time_s < end_plan_time_s - 0.5 * PERIOD_S:
                return False
            if any(deserialize_message(command, JointState).effort) or header_stamp_ns(command) < header_stamp_ns(
                    tracking):
                return False
            first_zero.append(client.bag.counts["/joint_commands"])
        return client.bag.counts["/joint_commands"] >= first_zero[0] + zeros - 1
    return recorded


def test_killing_the_simulator_makes_the_tracker_zero_its_torque(ros_domain, tmp_path):
    from swim_interfaces.action import ExecutePlan
    with maneuver_under_way(tmp_path, "sim", CONSTRAINED_SHORT) as (system, client, _, result):
        kill(system, "sim_node")
        outcome = client.wait_for(result, STATE_LOST_RESULT_TIMEOUT_S, "end of the goal").result
        client.spin_until(watchdog_zeros_recorded(client, outcome.duration_s, 20), MESSAGE_TIMEOUT_S,
                          "the commands up to the end and 20 of the watchdog's zeros, recorded")
        assert system.dead() == ["sim_node"]   # the tracker and the planner carry on
        client.close()
        topics = read_back(tmp_path / "bag", client.bag.counts)
    assert outcome.error_code == ExecutePlan.Result.STATE_LOST
    assert KILL_AT_PLAN_TIME_S <= outcome.duration_s < 9.0
    # in the order published (the recorder may lag a lock-step loop, so not by the time of receipt): the last
    # torque the tracker commanded answered the last state it tracked, the one that ended the goal (its plan time
    # from the plan's first torque is the goal's duration, within a period), a state the simulator published
    # (recorded, or one of the periods' states the simulator had not yet delivered to the lagging recorder when it
    # was killed, lost with it: on its 8 ms grid after the last recorded one, 200 of them on a loaded host); after
    # it, only zero commands (one each period of the watchdog, 20 of them at least)
    efforts = [list(m.effort) for _, m in topics["/joint_commands"]]
    first_torque = min(i for i, effort in enumerate(efforts) if effort != [0.0, 0.0])
    last_torque = max(i for i, effort in enumerate(efforts) if effort != [0.0, 0.0])
    state_stamps = {stamp_ns(m) for _, m in topics["/joint_states"]}
    answered_ns = stamp_ns(topics["/joint_commands"][last_torque][1])
    period_ns = round(PERIOD_S * 1e9)
    tracked_ns = answered_ns - stamp_ns(topics["/joint_commands"][first_torque][1])
    around = [(stamp_ns(m), m.effort.tolist()) for _, m in topics["/joint_commands"][last_torque - 2:last_torque + 3]]
    plan_times = [m.plan_time_s for _, m in topics["/tracking_state"]][-3:]
    assert abs(tracked_ns - outcome.duration_s * 1e9) <= period_ns, f"commands {around}, plan times {plan_times}"
    undelivered_periods, off_grid_ns = divmod(answered_ns - max(state_stamps), period_ns)
    assert answered_ns in state_stamps or (undelivered_periods > 0 and off_grid_ns == 0)
    assert len(efforts) - last_torque - 1 >= 20


def test_killing_the_tracker_makes_the_bridge_zero_the_torque(ros_domain, tmp_path):
    with maneuver_under_way(tmp_path, "bridge", FREE_SHORT, plant_overrides=("diagnostics_rate_hz:=20.0",)) as (
            system, client, _, result):
        killed_ns = kill(system, "tracker_node")
        settled_ns = killed_ns + WATCHDOG_SETTLE_S * 1e9
        sampled = sampled_stamps(client, "/joint_states")
        diagnosed = sampled_stamps(client, "/diagnostics", DiagnosticArray)
        def settled_and_recorded() -> bool:
            # the assertions read the bag: wait until the recorder, not only this sampler, has the 20th state
            settled = sorted(s for s in sampled if s > settled_ns)
            recorded = client.latest_cdr.get("/joint_states")
            return len(settled) >= 20 and max(diagnosed) > settled_ns and recorded is not None \
                and header_stamp_ns(recorded) >= settled[19]
        client.spin_until(settled_and_recorded, MESSAGE_TIMEOUT_S, "states and diagnostics after the watchdog")
        assert system.dead() == ["tracker_node"] and not result.done()
        client.close()
        topics = read_back(tmp_path / "bag", client.bag.counts)
    # the bridge stamps each state with the wall clock at its sample: compared with the kill's wall time
    states = [m for _, m in topics["/joint_states"]]
    assert any(np.any(np.array(m.effort[2:]) != 0.0) for m in states if stamp_ns(m) < killed_ns)   # torque before
    settled = [m for m in states if stamp_ns(m) > settled_ns]
    assert len(settled) >= 20                                   # the bridge keeps sampling the rig
    # with no torque driving either motor: zero (the watchdog's), or the safety layer's braking of a link that coasts
    # toward its hard limit (swim_hw_bridge.safety: against its velocity, the limit on the side it moves to)
    for m in settled:
        assert list(m.effort[:2]) == [0.0, 0.0]   # alpha and R have no motor
        for effort, position, velocity in zip(m.effort[2:], m.position[2:], m.velocity[2:]):
            assert effort == 0.0 or (effort * velocity < 0.0 and position * velocity > 0.0), \
                f"effort {list(m.effort)} at {list(m.position)} moving {list(m.velocity)}"
    # the torque went to zero for the watchdog's reason, reported on /diagnostics
    statuses = [status for _, array in topics["/diagnostics"] if stamp_ns(array) > settled_ns
                for status in array.status if status.name.startswith("/bridge_node")]
    assert statuses
    values = {kv.key: kv.value for kv in statuses[-1].values}
    assert values["watchdog"] == "EXPIRED" and values["lifecycle_state"] == "active"
    # the torque it reports is the watchdog's zero, or the braking rule's full torque limit on a coasting link
    for key, torque_limit_n_m in zip(("heave_torque_n_m", "pitch_torque_n_m"), load_rig().limits.torque_limits_n_m):
        torque_n_m = float(values[key])
        assert torque_n_m == 0.0 or abs(torque_n_m) == pytest.approx(torque_limit_n_m, rel=1e-12), (key, torque_n_m)


def test_killing_the_tracker_leaves_the_lock_step_simulator_waiting(ros_domain, tmp_path):
    with maneuver_under_way(tmp_path, "sim", CONSTRAINED_SHORT) as (system, client, _, result):
        kill(system, "tracker_node")
        sampled = sampled_stamps(client, "/joint_states")
        # resend_after_s is 0.5 s (sim_node's default): the last state published is published again
        client.spin_until(lambda: len(sampled) > 1 and sampled.count(max(sampled)) >= 2, MESSAGE_TIMEOUT_S,
                          "a resent state")
        assert system.dead() == ["tracker_node"] and not result.done()
        client.close()
        topics = read_back(tmp_path / "bag", client.bag.counts)
    # lock-step: the simulator steps only on the command stamped like its state, so simulated time stopped at the
    # state that answers the last command it received; that state, the one it waits on, is published again (seen
    # live, above: the recorder may not have written the resend yet when it closes) and no later one is. The
    # commands the tracker had sent but the recorder had not yet received died with the tracker (the recorder may
    # lag a lock-step loop by a few hundred periods on a loaded host, and may start after the first state): every
    # recorded command from the first recorded state on answers a recorded state before the waiting one, and the
    # recorded states run on the 8 ms grid, one each period.
    period_ns = round(PERIOD_S * 1e9)
    waiting_ns = max(sampled)
    state_stamps = sorted({stamp_ns(m) for _, m in topics["/joint_states"]})
    command_stamps = {stamp_ns(m) for _, m in topics["/joint_commands"]}
    assert state_stamps[-1] <= waiting_ns
    assert max(command_stamps) <= waiting_ns - period_ns
    assert {stamp for stamp in command_stamps if stamp >= state_stamps[0]} <= set(state_stamps)
    assert set(np.diff(state_stamps)) <= {period_ns}


def test_killing_the_planner_mid_execution_lets_the_tracker_finish(ros_domain, tmp_path):
    from swim_interfaces.action import ExecutePlan
    with maneuver_under_way(tmp_path, "sim", CONSTRAINED_SHORT) as (system, client, plan, result):
        kill(system, "planner_node")
        outcome = client.wait_for(result, PLAN_END_TIMEOUT_S, "end of the goal").result
        client.drain(outcome.duration_s)
        assert system.dead() == ["planner_node"]
        client.close()
        topics = read_back(tmp_path / "bag", client.bag.counts)
    assert outcome.error_code == ExecutePlan.Result.SUCCESSFUL
    assert outcome.duration_s == pytest.approx(plan.time_from_start_s[-1], abs=1e-9)
    plan_times = [m.plan_time_s for _, m in topics["/tracking_state"]]
    assert plan_times[0] == 0.0 and plan_times[-1] == pytest.approx(plan.time_from_start_s[-1], abs=1e-9)
    assert len(topics["/plan"]) == 1


def test_a_node_killed_mid_run_is_named_by_the_recorded_runs_error(ros_domain, tmp_path):
    """swim-demo's and swim-experiments' run (recorded_run.run_recorded): the simulator killed while the maneuver
    runs ends the run with NodeDied, which names it once and says where its log is."""
    import subprocess

    from swim_bringup.recorded_run import run_recorded
    from swim_bringup.run_client import NodeDied
    config = shared_host_config("paper", tmp_path)
    simulator_parameters = str(config / "sim.yaml")   # on the simulator's command line only
    killed = []

    def kill_the_simulator_once_under_way(fraction: float) -> None:
        if fraction >= 0.1 and not killed:
            killed.append(subprocess.run(["pkill", "-KILL", "-f", simulator_parameters]).returncode)

    with pytest.raises(NodeDied) as raised:
        run_recorded(closed_loop_specs(config, visualization=False), tmp_path / "run", *CONSTRAINED_SHORT, 1.0,
                     PLAN_END_TIMEOUT_S, progress=kill_the_simulator_once_under_way)
    assert killed == [0]
    assert raised.value.nodes == ("sim_node",)
    # seen in the goal's feedback, or after the goal ended (STATE_LOST, named before it)
    message = str(raised.value)
    assert message.endswith(f"sim_node died (see {tmp_path / 'run' / 'logs'})") and message.count("died") == 1
