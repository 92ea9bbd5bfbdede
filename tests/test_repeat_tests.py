"""scripts/repeat_tests.sh, the flake hunter: on a test that fails every other run and one that always passes, run
from a working directory outside the repository; the busy-loop process of --load gone afterwards, also after Ctrl-C;
usage errors."""
import os
import re
import signal
import subprocess
import textwrap
import time
from pathlib import Path

import pytest
from conftest import WORKSPACE

from swim_ros.processes import run_child, start_child

SCRIPT = WORKSPACE / "scripts" / "repeat_tests.sh"
# Generous against pytest's start-up (about 1 s per run here, more on a loaded host) times the runs of a call.
SCRIPT_TIMEOUT_S = 120.0
#: the sample's slow test: far longer than the poll below takes to see its start file and send the Ctrl-C, which
#: ends it, so its length costs nothing
SLOW_SAMPLE_TEST_S = 60
#: how often the test looks for the slow test's start file: a file has no event to wait on; 50 ms costs nothing
START_FILE_POLL_S = 0.05


def script_env(tmp_path: Path) -> dict[str, str]:
    """The script's temporary folders in tmp_path; no third-party pytest plugins in the runs (the sample tests need
    none, and loading them, hypothesis above all, costs about 2 s per run)."""
    return {**os.environ, "TMPDIR": str(tmp_path), "PYTEST_DISABLE_PLUGIN_AUTOLOAD": "1"}


@pytest.fixture()
def sample(tmp_path) -> Path:
    """A test file: test_flaky fails in the first, third, ... run (a counter file beside it), test_passes never."""
    path = tmp_path / "test_sample.py"
    path.write_text(textwrap.dedent(f"""\
        from pathlib import Path

        COUNTER = Path({str(tmp_path / "counter")!r})


        def test_flaky():
            runs_before = int(COUNTER.read_text()) if COUNTER.exists() else 0
            COUNTER.write_text(str(runs_before + 1))
            assert runs_before % 2 == 1, f"flaky on run {{runs_before + 1}}"


        def test_passes():
            pass
        """))
    return path


def repeat(tmp_path: Path, *arguments: str) -> subprocess.CompletedProcess:
    """The script run from tmp_path."""
    return run_child([str(SCRIPT), *arguments], cwd=tmp_path, env=script_env(tmp_path), capture_output=True,
                     text=True, timeout_s=SCRIPT_TIMEOUT_S)


def load_pid(output: str) -> int:
    match = re.search(r"^load: one core kept busy \(pid (\d+)\)$", output, re.MULTILINE)
    assert match, output
    return int(match.group(1))


def test_flaky_test_counted_with_its_reason(tmp_path, sample):
    result = repeat(tmp_path, "4", str(sample))
    lines = result.stdout.splitlines()
    assert result.returncode == 1, result.stdout + result.stderr
    assert lines[-1] == "repeat: 4 runs, 2 failures"
    table = lines[lines.index(next(line for line in lines if line.startswith("test "))):]
    # the test id is relative to the inner runs' rootdir, which depends on where the clone and tmp_path lie
    assert re.search(r"^(\S+/)?test_sample\.py::test_flaky +2/4 +AssertionError: flaky on run 1 \| "
                     r"assert \(0 % 2\) == 1$",
                     "\n".join(table), re.MULTILINE), result.stdout
    assert not any("test_passes" in line for line in table), result.stdout
    # the runs' output is kept for inspection where the report says
    kept = re.search(r"^the runs' pytest output and junit files: (.+)$", result.stdout, re.MULTILINE)
    assert kept and Path(kept.group(1)).parent == tmp_path
    assert sorted(path.name for path in Path(kept.group(1)).glob("run-*.xml")) == [f"run-{k}.xml" for k in range(1, 5)]


def test_passing_test_under_load(tmp_path, sample):
    result = repeat(tmp_path, "2", "--load", str(sample), "-k", "passes")
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.splitlines()[-1] == "repeat: 2 runs, 0 failures"
    assert not Path(f"/proc/{load_pid(result.stdout)}").exists()
    assert not list(tmp_path.glob("repeat_tests.*"))


def test_ctrl_c_stops_the_runs_and_the_load(tmp_path):
    started = tmp_path / "started"
    (tmp_path / "test_slow.py").write_text(textwrap.dedent(f"""\
        import time
        from pathlib import Path


        def test_slow():
            Path({str(started)!r}).touch()
            time.sleep({SLOW_SAMPLE_TEST_S})
        """))
    # A terminal's Ctrl-C: SIGINT to the script's process group, SIGINT not ignored whatever this test inherited.
    process = start_child([str(SCRIPT), "3", "--load", str(tmp_path / "test_slow.py")], cwd=tmp_path,
                          env=script_env(tmp_path), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, start_new_session=True,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + SCRIPT_TIMEOUT_S
        while not started.exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(START_FILE_POLL_S)
        assert started.exists(), "the slow test never started"
        os.killpg(process.pid, signal.SIGINT)
        stdout, stderr = process.communicate(timeout=SCRIPT_TIMEOUT_S)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.returncode == 130, stdout + stderr
    assert "interrupted: 0 of 3 runs completed" in stdout
    assert stdout.splitlines()[-1] == "repeat: 0 runs, 0 failures"
    assert not Path(f"/proc/{load_pid(stdout)}").exists()


@pytest.mark.parametrize("arguments", [[], ["0"], ["many", "tests"], ["--load"]])
def test_usage_errors(tmp_path, arguments):
    result = repeat(tmp_path, *arguments)
    assert result.returncode == 2, result.stdout + result.stderr
    assert "usage: scripts/repeat_tests.sh N [--load] [PYTEST ARGS ...]" in result.stderr


def test_arguments_pytest_rejects_are_a_usage_error(tmp_path):
    result = repeat(tmp_path, "3", "--no-such-pytest-option")
    assert result.returncode == 2, result.stdout + result.stderr
    assert "unrecognized arguments: --no-such-pytest-option" in result.stderr
    assert "run 2/3" not in result.stdout
