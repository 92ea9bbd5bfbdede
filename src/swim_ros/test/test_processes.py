"""swim_ros.processes in real processes (no DDS): a child started by start_child ends when its starter is killed,
also when the starter dies within milliseconds of the fork (before the child could set its parent-death signal);
`ros2 run` runs the executable itself; run_child kills what outlives its timeout; interrupt_on_sigterm makes SIGTERM
a Ctrl-C; the command-line form for shell scripts."""
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import pytest

from swim_ros.processes import ORPHAN_EXIT_STATUS, executable_command, run_child, start_child, with_parent_death_signal
from swim_ros.testing.processes import processes_left, tagged_processes

#: how long a child may take to notice its starter's death and end: the signal is immediate, `sleep` dies of it
END_TIMEOUT_S = 10.0
#: a starter killed this many times at a random moment within KILL_WINDOW_S of its fork
RACE_TRIES = 20
KILL_WINDOW_S = 0.006
#: the tag a test's processes carry in their environment, to find them whatever their parent
TAG_VARIABLE = "SWIM_PROCESSES_TEST"

pytestmark = pytest.mark.skipif(shutil.which("setpriv") is None,
                                reason="util-linux's setpriv is missing: no parent-death signal")


def tagged(tag: str) -> list[int]:
    return list(tagged_processes(TAG_VARIABLE, tag))


def wait_until_none_left(tag: str, timeout_s: float = END_TIMEOUT_S) -> list[str]:
    return processes_left(TAG_VARIABLE, tag, timeout_s)


def starter(script: str, tag: str) -> subprocess.Popen:
    """python -c script, its processes tagged tag; its stdout readable line by line."""
    return start_child([sys.executable, "-c", textwrap.dedent(script)], stdout=subprocess.PIPE, text=True,
                       env={**os.environ, TAG_VARIABLE: tag})


def test_a_child_ends_when_its_starter_is_killed():
    tag = uuid.uuid4().hex
    process = starter("""
        from swim_ros.processes import start_child
        child = start_child(["sleep", "60"])
        print(child.pid, flush=True)
        child.wait()
        """, tag)
    child_pid = int(process.stdout.readline())
    assert Path(f"/proc/{child_pid}").exists()
    process.kill()
    process.wait()
    assert wait_until_none_left(tag) == []


def test_a_child_whose_starter_died_before_the_signal_was_set_does_not_run(tmp_path):
    """The child's check: a parent that is not the starter (here: this test, standing for init) means the starter
    is gone and no signal will come."""
    marker = tmp_path / "ran"
    result = subprocess.run(with_parent_death_signal(["touch", str(marker)], starter_pid=os.getpid() + 1_000_000),
                            timeout=END_TIMEOUT_S)
    assert result.returncode == ORPHAN_EXIT_STATUS and not marker.exists()
    result = subprocess.run(with_parent_death_signal(["touch", str(marker)]), timeout=END_TIMEOUT_S)
    assert result.returncode == 0 and marker.exists()


def test_a_starter_killed_right_after_the_fork_leaves_no_child():
    """A starter killed by a thread of its own at a random moment within milliseconds of the fork: on this host the
    child's parent-death signal alone (setpriv's, without the check) left a child alive in about one try in ten."""
    tag = uuid.uuid4().hex
    for attempt in range(RACE_TRIES):
        process = starter(f"""
            import os, random, signal, threading, time
            from swim_ros.processes import start_child
            delay_s = random.uniform(0.0, {KILL_WINDOW_S})
            threading.Thread(target=lambda: (time.sleep(delay_s), os.kill(os.getpid(), signal.SIGKILL))).start()
            start_child(["sleep", "60"])
            time.sleep(60)
            """, tag)
        process.wait(timeout=END_TIMEOUT_S)
    assert wait_until_none_left(tag) == []


def test_ros2_run_is_the_executable_itself(tmp_path):
    executable = tmp_path / "lib" / "swim_demo_package" / "demo_node"
    executable.parent.mkdir(parents=True)
    executable.write_text("#!/bin/sh\n")
    executable.chmod(0o755)
    environment = {"AMENT_PREFIX_PATH": f"/nonexistent:{tmp_path}"}
    command = ["ros2", "run", "swim_demo_package", "demo_node", "--ros-args", "-p", "a:=1"]
    assert executable_command(command, environment) == [str(executable), "--ros-args", "-p", "a:=1"]
    assert executable_command(["ros2", "run", "swim_demo_package", "other"], environment)[:2] == ["ros2", "run"]
    assert executable_command(["sleep", "1"], environment) == ["sleep", "1"]


def test_run_child_kills_a_child_that_outlives_its_timeout():
    tag = uuid.uuid4().hex
    started = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        run_child(["sleep", "60"], timeout_s=0.5, env={**os.environ, TAG_VARIABLE: tag})
    assert time.monotonic() - started < END_TIMEOUT_S and tagged(tag) == []
    result = run_child(["sh", "-c", "cat; echo done >&2"], input="in\n", capture_output=True, text=True,
                       timeout_s=END_TIMEOUT_S)
    assert (result.returncode, result.stdout, result.stderr, result.args) == (0, "in\n", "done\n",
                                                                              ["sh", "-c", "cat; echo done >&2"])


def test_interrupt_on_sigterm_lets_a_cli_stop_what_it_started():
    process = start_child([sys.executable, "-c", textwrap.dedent("""
        import time
        from swim_ros.processes import interrupt_on_sigterm
        interrupt_on_sigterm()
        try:
            print("ready", flush=True)
            time.sleep(60)
        finally:
            print("stopped", flush=True)
        """)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "ready"
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=END_TIMEOUT_S)
    assert out.strip() == "stopped" and "KeyboardInterrupt" in err


def with_python_on_path(tag: str) -> dict[str, str]:
    """This process's environment, tagged tag, with this interpreter first on PATH (for `python -m` in a script)."""
    return {**os.environ, TAG_VARIABLE: tag, "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}"}


def test_a_shell_scripts_child_ends_with_the_script():
    """`python -m swim_ros.processes $$ command &` in a bash script killed outright: the command runs (the child's
    pid executes python, setpriv, sh, then sleep itself) and ends with the script."""
    tag = uuid.uuid4().hex
    script = 'python -m swim_ros.processes "$$" sleep 60 & echo $!; wait'
    process = start_child(["bash", "-c", script], stdout=subprocess.PIPE, text=True, env=with_python_on_path(tag))
    child_pid = int(process.stdout.readline())
    deadline = time.monotonic() + END_TIMEOUT_S
    while Path(f"/proc/{child_pid}/comm").read_text().strip() != "sleep":
        assert time.monotonic() < deadline, "the script's command never ran"
        time.sleep(0.05)
    process.kill()
    process.wait()
    assert wait_until_none_left(tag) == []


def test_a_background_commands_own_pid_is_refused_as_its_starter():
    """bash expands `"$BASHPID"` of a background command in the child it forked: that pid is the child's own."""
    tag = uuid.uuid4().hex
    script = 'python -m swim_ros.processes "$BASHPID" sleep 60 & wait $!'
    result = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=END_TIMEOUT_S,
                            env=with_python_on_path(tag))
    assert result.returncode == 1 and "is this process, not its starter" in result.stderr
    assert tagged(tag) == []
