"""swim-bringup: which nodes with which parameters (tests/test_launch_files.py holds them to the launch files'),
bad input refused, and over DDS the installed command as an operator runs it: a node killed is reported with its
exit status and log tail and the rest are stopped (exit 1), or with --keep-going kept up until SIGINT (exit 0); a
SIGTERM while the nodes start stops them. No process it started outlives it: each run carries an environment
variable of its own, and no process that holds it may remain."""
import os
import re
import signal
import subprocess
import time
import uuid
from pathlib import Path

import pytest

from swim_bringup.bringup import LOG_TAIL_LINES, bringup_specs, exit_status, log_tail, main
from swim_bringup.system import LOCKSTEP_STALE_OVERRIDE, closed_loop_specs, config_dir
from swim_ros.processes import STOP_GRACE_S, start_child
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, new_rclpy_context, ros_domain  # noqa: F401
from swim_ros.testing.processes import processes_left, tagged_processes

#: the variable that marks every process a test's swim-bringup starts (children inherit the environment)
TAG_VARIABLE = "SWIM_BRINGUP_TEST_RUN"
#: the default set's six nodes started at once and discovered: several s on a loaded 2-core host (each imports
#: rclpy and its models, the planner loads its library); 60 s margin, as the launch files' test
NODES_UP_TIMEOUT_S = 60.0
#: from a signal or a death to swim-bringup's exit: its look every 0.2 s, then SIGINT to the nodes and at worst
#: their SIGKILL after the grace period; 20 s more for a loaded host
EXIT_TIMEOUT_S = STOP_GRACE_S + 20.0
NODES = ("sim_node", "planner_node", "tracker_node", "maneuver_node", "rig_state_publisher", "marker_node")
NODE_LINE = re.compile(r"^\s+(\w+)\s+pid (\d+)\s", re.MULTILINE)


# --- which nodes, and bad input (no DDS) ---------------------------------------------------------------------------
def test_swim_bringup_adds_the_maneuver_server_and_the_runs_do_not():
    config = config_dir()
    assert "maneuver_node" not in [s.executable for s in closed_loop_specs(config)]   # swim-demo's, the runs'
    specs = {s.executable: s for s in bringup_specs("sim")}
    assert list(specs) == list(NODES)
    assert specs["maneuver_node"].params_file == config / "maneuver.yaml"
    assert specs["sim_node"].parameters == () and LOCKSTEP_STALE_OVERRIDE in specs["tracker_node"].parameters
    realtime = {s.executable: s for s in bringup_specs("sim", realtime=True)}
    assert realtime["sim_node"].parameters == ("mode:=realtime",)
    assert LOCKSTEP_STALE_OVERRIDE not in realtime["tracker_node"].parameters
    bridge = {s.executable: s for s in bringup_specs("bridge", "mf624", "paper", sliding_mode=False)}
    assert bridge["bridge_node"].parameters == ("backend:=mf624",)
    assert bridge["tracker_node"].parameters == ("sliding_mode_enabled:=false",)
    assert {s.params_file.parent for s in bridge.values() if s.params_file} == {config_dir("paper")}
    watched = {s.executable: s for s in bringup_specs("bridge", foxglove_port=9001)}
    assert list(watched) == [*[s.executable for s in bringup_specs("bridge")],
                             "foxglove_node"]
    assert watched["foxglove_node"].package == "swim_viz" and watched["foxglove_node"].parameters == ("port:=9001",)


@pytest.mark.parametrize("arguments, reason", [
    (["sim", "--backend", "mf624"], "--backend is bridge_node's"),
    (["bridge", "--realtime"], "--realtime is sim_node's"),
    (["sim", "--config", "/nonexistent/swim"], "--config /nonexistent/swim: no such folder"),
    (["bridge", "--config", "EMPTY"], "no parameter file bridge_node: "),
    (["sim", "--foxglove", "70000"], "--foxglove takes a TCP port (0-65535), not 70000"),
])
def test_bad_input_exits_2_with_one_line_and_starts_nothing(tmp_path, capsys, arguments, reason):
    (tmp_path / "empty").mkdir()
    arguments = [str(tmp_path / "empty") if a == "EMPTY" else a for a in arguments]
    assert main([*arguments, "--log-dir", str(tmp_path / "logs")]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1 and err.startswith("swim-bringup: ") and reason in err, err
    assert not (tmp_path / "logs").exists()


def test_an_unknown_set_or_backend_is_a_usage_error(capsys):
    for arguments in (["mars"], ["bridge", "--backend", "can"]):
        with pytest.raises(SystemExit) as exit_info:
            main(arguments)
        assert exit_info.value.code == 2
        assert "invalid choice" in capsys.readouterr().err


def test_a_death_reads_as_its_exit_status_and_log_tail(tmp_path):
    assert exit_status(-signal.SIGKILL) == "killed by SIGKILL" and exit_status(3) == "exit status 3"
    log = tmp_path / "node.log"
    log.write_text("".join(f"line {k}\n" for k in range(50)))
    assert log_tail(log) == [f"line {k}" for k in range(50 - LOG_TAIL_LINES, 50)]
    assert log_tail(tmp_path / "missing.log")[0].startswith("(log unreadable: ")


# --- the installed command over DDS ---------------------------------------------------------------------------------
def tagged(tag: str) -> list[int]:
    return list(tagged_processes(TAG_VARIABLE, tag))


class Bringup:
    """swim-bringup ARGUMENTS as an operator runs it (the installed console script, in the test's ROS domain), its
    output in a file, its processes tagged."""

    def __init__(self, tmp_path: Path, *arguments: str) -> None:
        from ament_index_python.packages import get_package_prefix
        executable = Path(get_package_prefix("swim_bringup")) / "lib" / "swim_bringup" / "swim-bringup"
        self.tag = uuid.uuid4().hex
        tmp_path.mkdir(parents=True, exist_ok=True)
        self.log_dir = tmp_path / "logs"
        self.output_path = tmp_path / "swim-bringup.out"
        with open(self.output_path, "w") as output:
            self.process = start_child([str(executable), *arguments, "--log-dir", str(self.log_dir)],
                                       stdout=output, stderr=subprocess.STDOUT,
                                       env={**os.environ, TAG_VARIABLE: self.tag})

    def output(self) -> str:
        return self.output_path.read_text()

    def wait_for_output(self, pattern: str, timeout_s: float) -> re.Match:
        deadline = time.monotonic() + timeout_s
        while True:
            ended = self.process.poll() is not None   # before reading: all it wrote is then in the file
            match = re.search(pattern, self.output(), re.MULTILINE)
            if match is not None:
                return match
            assert not ended, f"swim-bringup ended ({self.process.returncode}) without {pattern!r}:\n{self.output()}"
            assert time.monotonic() < deadline, f"no {pattern!r} within {timeout_s} s:\n{self.output()}"
            time.sleep(0.05)

    def pids(self) -> dict[str, int]:
        """The nodes' pids as swim-bringup printed them."""
        self.wait_for_output(r"Ctrl-C stops them", NODES_UP_TIMEOUT_S)
        return {name: int(pid) for name, pid in NODE_LINE.findall(self.output())}

    def wait_until_up(self) -> dict[str, int]:
        """Every node started and discovered in the graph; their pids."""
        import rclpy
        pids = self.pids()
        assert sorted(pids) == sorted(NODES)
        with new_rclpy_context() as context:
            probe = rclpy.create_node("bringup_probe", context=context)
            try:
                deadline = time.monotonic() + NODES_UP_TIMEOUT_S
                while not set(NODES) <= set(probe.get_node_names()):
                    assert self.process.poll() is None, self.output()
                    assert time.monotonic() < deadline, f"nodes up: {probe.get_node_names()}\n{self.output()}"
                    time.sleep(0.1)
            finally:
                probe.destroy_node()
        return pids

    def wait_for_exit(self) -> int:
        try:
            return self.process.wait(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            pytest.fail(f"swim-bringup still running {EXIT_TIMEOUT_S} s on:\n{self.output()}")

    def close(self) -> list[str]:
        """SIGKILL swim-bringup and every process it left (a failed test's); those that were left, described."""
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        return processes_left(TAG_VARIABLE, self.tag, timeout_s=0.0)


@pytest.fixture()
def bringup(tmp_path, request):
    """A factory of Bringup runs in the test session's ROS domain; whatever they leave is killed after the test."""
    request.getfixturevalue("ros_domain")
    runs: list[Bringup] = []

    def start(*arguments: str) -> Bringup:
        runs.append(Bringup(tmp_path / f"run{len(runs)}", *arguments))
        return runs[-1]
    yield start
    for run in runs:
        run.close()


def kill_when_it_has_logged(run: Bringup, executable: str, pid: int) -> None:
    """SIGKILL the node once its log holds a line (a node is in the graph before it logs its start)."""
    log_path = run.log_dir / f"{executable}.log"
    deadline = time.monotonic() + MESSAGE_TIMEOUT_S
    while not log_path.read_text().strip():
        assert time.monotonic() < deadline, f"{executable} logged nothing"
        time.sleep(0.05)
    os.kill(pid, signal.SIGKILL)


def assert_death_reported(run: Bringup, executable: str, pid: int, status: str) -> None:
    """swim-bringup's report of a node's end: its pid, exit status and the last lines of its log, in order."""
    log_path = run.log_dir / f"{executable}.log"
    run.wait_for_output(rf"{executable} \(pid {pid}\) ended, {status}; its log {log_path} ends:", MESSAGE_TIMEOUT_S)
    output = run.output()
    tail = log_path.read_text().splitlines()[-LOG_TAIL_LINES:]
    assert "\n".join(f"  | {line}" for line in tail) in output


def test_a_node_that_dies_is_reported_and_the_rest_stopped(bringup):
    run = bringup("sim")
    pids = run.wait_until_up()
    kill_when_it_has_logged(run, "tracker_node", pids["tracker_node"])
    assert run.wait_for_exit() == 1
    assert_death_reported(run, "tracker_node", pids["tracker_node"], "killed by SIGKILL")
    assert "swim-bringup: every node stopped" in run.output()
    assert tagged(run.tag) == []
    assert sorted(p.stem for p in run.log_dir.glob("*.log")) == sorted(NODES)


def test_keep_going_reports_a_death_keeps_the_rest_up_and_sigint_stops_them(bringup):
    run = bringup("sim", "--keep-going")
    pids = run.wait_until_up()
    kill_when_it_has_logged(run, "tracker_node", pids["tracker_node"])
    run.wait_for_output(r"--keep-going: .* stay up", MESSAGE_TIMEOUT_S)
    assert_death_reported(run, "tracker_node", pids["tracker_node"], "killed by SIGKILL")
    time.sleep(0.5)   # a few of swim-bringup's looks: it must not stop the others
    assert run.process.poll() is None
    alive = set(tagged(run.tag))
    assert {pids[n] for n in NODES if n != "tracker_node"} <= alive and pids["tracker_node"] not in alive
    run.process.send_signal(signal.SIGINT)
    assert run.wait_for_exit() == 0
    assert "swim-bringup: SIGINT: stopping the nodes" in run.output()
    assert tagged(run.tag) == []


@pytest.mark.parametrize("when", [r"swim-bringup: starting the sim set", r"^\s+marker_node\s+pid \d+"])
def test_sigterm_while_the_nodes_start_leaves_nothing(bringup, when):
    """SIGTERM as soon as swim-bringup says it starts the nodes (its handlers are in; the signal lands while it
    starts them or just after) and as soon as it has started them (each still importing, not yet in the graph)."""
    run = bringup("sim")
    run.wait_for_output(when, NODES_UP_TIMEOUT_S)
    run.process.send_signal(signal.SIGTERM)
    assert run.wait_for_exit() == 0
    assert tagged(run.tag) == []


def test_a_killed_swim_bringup_takes_its_nodes_with_it(bringup):
    """SIGKILL leaves swim-bringup no chance to stop its nodes: the kernel's parent-death signal
    (swim_ros.processes.PARENT_DEATH_SIGNAL) stops them."""
    run = bringup("sim")
    run.wait_until_up()
    run.process.kill()
    run.process.wait()
    deadline = time.monotonic() + EXIT_TIMEOUT_S
    while tagged(run.tag):
        assert time.monotonic() < deadline, f"left running: {tagged(run.tag)}"
        time.sleep(0.1)
