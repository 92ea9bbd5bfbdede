"""Benchmark: wall time of the README's main command (swim-demo: bring-up, the paper's 30 s constrained maneuver
in lock-step simulation, recording, analysis, figures, shut-down), each in a fresh temporary run folder.

RUNS lists what is timed; the paper's experiments (swim-experiments) get their entry there. Prints one JSON line.
"""
from __future__ import annotations

import json
import subprocess
import tempfile
import time
from pathlib import Path

#: name -> command, timed from start to exit; "{run_dir}" becomes a fresh temporary folder
RUNS: dict[str, list[str]] = {
    "demo": ["ros2", "run", "swim_bringup", "swim-demo", "--run-dir", "{run_dir}"],
    # "experiments": [...],   # the paper's experiments (swim-experiments): add their command here
}


def wall_time_s(command: list[str]) -> float:
    """Seconds from start to exit of command run in a fresh run folder; raises if it fails."""
    with tempfile.TemporaryDirectory() as work:
        arguments = [a.replace("{run_dir}", str(Path(work) / "run")) for a in command]
        started = time.perf_counter()
        subprocess.run(arguments, check=True, capture_output=True)
        return time.perf_counter() - started


def main() -> None:
    times = {f"{name}_wall_time_s": round(wall_time_s(command), 1) for name, command in RUNS.items()}
    print(json.dumps({"benchmark": "demo_wall_time", **times}))


if __name__ == "__main__":
    main()
