"""Style is a test too: pycodestyle errors/warnings and pyflakes over every package, test and benchmark."""
import subprocess
import sys

from conftest import WORKSPACE

#: ruff checks the whole tree in about a second; 120 s only stops a hung process
RUFF_TIMEOUT_S = 120


def test_ruff_finds_nothing():
    result = subprocess.run([sys.executable, "-m", "ruff", "check", "--output-format", "concise",
                             "src", "tests", "bench"], cwd=WORKSPACE, capture_output=True, text=True,
                            timeout=RUFF_TIMEOUT_S)
    assert result.returncode == 0, result.stdout + result.stderr
