"""The report of scripts/repeat_tests.sh.

Each test that failed in at least one of the runs, in how many, and the first failure's reason; the last line
`repeat: N runs, F failures`. Exit status 0 when no run failed, else 1.

usage: repeat_tests_report.py RUN_DIR RUNS

RUN_DIR holds, for each run k = 1..RUNS, run-k.xml (pytest's junit XML, junit_family xunit1 for the file
attribute), run-k.status (pytest's exit status) and run-k.log (its output). A run fails when a test in it failed or
errored, or when pytest did not exit normally (a crash writes no junit file): such a run without a failing test
is counted under the pseudo-test SESSION.
"""
import re
import signal
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

SESSION = "(pytest session)"
REASON_WIDTH = 100  # characters of a failure's reason shown; the rest stays in the run's junit file
PYTEST_STATUS = {1: "tests failed", 2: "interrupted", 3: "internal error", 4: "usage error", 5: "no tests collected"}


def test_id(case: ET.Element) -> str:
    """The pytest node id (path::Class::name) of a junit testcase.

    Made from its file attribute and dotted classname; `classname::name` when there is no file attribute to split
    the classname with.
    """
    classname, name, path = case.get("classname", ""), case.get("name", ""), case.get("file")
    if path:
        module = path.removesuffix(".py").replace("/", ".")
        if classname == module or classname.startswith(module + "."):
            classes = classname[len(module) + 1:].split(".") if classname != module else []
            return "::".join([path, *classes, name])
    return f"{classname}::{name}" if classname else name


def one_line(message: str) -> str:
    """A failure message as one line (its lines joined by ' | '), cut to REASON_WIDTH characters."""
    text = " | ".join(line.strip() for line in message.splitlines() if line.strip())
    text = re.sub(r"\s+", " ", text)
    return text if len(text) <= REASON_WIDTH else text[:REASON_WIDTH - 3] + "..."


def reason(problem: ET.Element) -> str:
    """A failure's or error's message.

    For a collection error, whose message says only that, the exception (the last `E ` line of the traceback) is
    appended.
    """
    message, text = problem.get("message") or "", problem.text or ""
    if message == "collection failure":
        exceptions = [line[1:].strip() for line in text.splitlines() if line.startswith("E ")]
        message = f"{message}: {exceptions[-1]}" if exceptions else message
    return message or text or "(no message)"


def signal_name(number: int) -> str:
    """The name of signal number (e.g. SIGKILL), or "unknown" when no signal has it."""
    try:
        return signal.Signals(number).name
    except ValueError:
        return "unknown"


def run_failures(run_dir: Path, run: int) -> tuple[dict[str, str], int]:
    """The failing tests of one run, each with its reason, and the number of tests it ran."""
    status_file = run_dir / f"run-{run}.status"
    status = int(status_file.read_text()) if status_file.exists() else None
    failures: dict[str, str] = {}
    tests = 0
    try:
        cases = ET.parse(run_dir / f"run-{run}.xml").getroot().iter("testcase")
        for case in cases:
            tests += 1
            problem = case.find("failure")
            if problem is None:
                problem = case.find("error")
            if problem is not None:
                failures.setdefault(test_id(case), one_line(reason(problem)))
        junit_note = "no failing test in its junit file"
    except FileNotFoundError:
        junit_note = "no junit file written"
    except ET.ParseError as error:
        junit_note = f"junit file unreadable ({error})"
    if status != 0 and not failures:
        if status is None:
            what = "exit status unknown"
        elif status > 128:
            what = f"killed by signal {status - 128} ({signal_name(status - 128)})"
        else:
            what = f"exit status {status} ({PYTEST_STATUS.get(status, 'unknown')})"
        failures[SESSION] = f"pytest {what}, {junit_note}"
    return failures, tests


def main(argv: list[str]) -> int:
    """Print the report of the runs in argv[1] (argv[2] of them); the exit status."""
    if len(argv) != 3 or not argv[2].isdigit():
        print(next(part for part in __doc__.split("\n\n") if part.startswith("usage:")), file=sys.stderr)
        return 2
    run_dir, runs = Path(argv[1]), int(argv[2])
    counts: dict[str, int] = {}
    first_reason: dict[str, str] = {}
    failed_runs = 0
    tests = set()
    for run in range(1, runs + 1):
        failures, ran = run_failures(run_dir, run)
        tests.add(ran)
        failed_runs += bool(failures)
        for test, reason in failures.items():
            counts[test] = counts.get(test, 0) + 1
            first_reason.setdefault(test, reason)
    if counts:
        rows = sorted(counts, key=lambda test: (-counts[test], test))
        width = max(len("test"), *(len(test) for test in rows))
        count_width = max(len("failed"), len(f"{runs}/{runs}"))
        print(f"\n{'test':<{width}}  {'failed':>{count_width}}  first failure")
        for test in rows:
            print(f"{test:<{width}}  {f'{counts[test]}/{runs}':>{count_width}}  {first_reason[test]}")
        print(f"\nthe runs' pytest output and junit files: {run_dir}")
    elif runs:
        print(f"no test failed; tests per run: {'/'.join(str(n) for n in sorted(tests))}")
    print(f"repeat: {runs} runs, {failed_runs} failures")
    return 1 if failed_runs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
