"""Types are a test too: mypy over every package's sources, strict on swim_model and the controller's math
(mypy.ini says what is checked and how strictly)."""
import sys

from conftest import WORKSPACE

from swim_ros.processes import run_child

#: mypy takes about 50 s with an empty cache (.mypy_cache) and a second or two with a warm one; 300 s only stops
#: a hung process
MYPY_TIMEOUT_S = 300


def test_mypy_finds_nothing():
    result = run_child([sys.executable, "-m", "mypy", "--config-file", "mypy.ini"], cwd=WORKSPACE,
                       capture_output=True, text=True, timeout_s=MYPY_TIMEOUT_S)
    assert result.returncode == 0, result.stdout + result.stderr
