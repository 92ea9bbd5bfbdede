"""Benchmark: wall time of the README's main command (swim-demo: bring-up, the paper's 30 s constrained maneuver
in lock-step simulation, recording, analysis, figures, shut-down) and of the paper's experiments (swim-experiments:
16 such runs), each in a fresh temporary run folder. Prints one JSON line.
"""
from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

from swim_ros.processes import interrupt_on_sigterm, run_child

#: name -> command, timed from start to exit; "{run_dir}" becomes a fresh temporary folder
RUNS: dict[str, list[str]] = {
    "demo": ["ros2", "run", "swim_bringup", "swim-demo", "--run-dir", "{run_dir}"],
    "experiments": ["ros2", "run", "swim_bringup", "swim-experiments", "--pipeline", "paper", "--seeds", "1",
                    "--run-dir", "{run_dir}"],  # 16 runs, the paper's pipeline
}


def wall_time_s(command: list[str]) -> tuple[float, int]:
    """Seconds from start to exit of command run in a fresh run folder, and its exit code (swim-experiments
    exits 1 when a run ended without reaching its goal: its wall time still counts)."""
    with tempfile.TemporaryDirectory() as work:
        arguments = [a.replace("{run_dir}", str(Path(work) / "run")) for a in command]
        started = time.perf_counter()
        completed = run_child(arguments, capture_output=True)
        return time.perf_counter() - started, completed.returncode


def main() -> None:
    interrupt_on_sigterm()   # SIGTERM stops the run under way as Ctrl-C does
    results = {}
    for name, command in RUNS.items():
        seconds, exit_code = wall_time_s(command)
        results[f"{name}_wall_time_s"], results[f"{name}_exit_code"] = round(seconds, 1), exit_code
    print(json.dumps({"benchmark": "demo_wall_time", **results}))


if __name__ == "__main__":
    main()
