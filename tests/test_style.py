"""Style is a test too: pycodestyle errors/warnings and pyflakes over every package, test and benchmark."""
import sys

from conftest import WORKSPACE

from swim_ros.processes import run_child

#: ruff checks the whole tree in about a second; 120 s only stops a hung process
RUFF_TIMEOUT_S = 120


def test_ruff_finds_nothing():
    result = run_child([sys.executable, "-m", "ruff", "check", "--output-format", "concise",
                        "src", "tests", "bench"], cwd=WORKSPACE, capture_output=True, text=True,
                       timeout_s=RUFF_TIMEOUT_S)
    assert result.returncode == 0, result.stdout + result.stderr


def test_no_module_a_user_runs_imports_a_testing_subpackage():
    """Test-only modules (stand-in hardware, replay checks) live in each package's ``testing`` subpackage, and
    only tests, benchmarks and other testing modules import them."""
    import re
    pattern = re.compile(r"^\s*(from|import)\s+\w+\.testing\b|^\s*from\s+\.+testing\b", re.MULTILINE)
    offenders = [str(path.relative_to(WORKSPACE)) for path in sorted((WORKSPACE / "src").glob("*/*/**/*.py"))
                 if "testing" not in path.parts and "test" not in path.parts and pattern.search(path.read_text())]
    assert offenders == []
