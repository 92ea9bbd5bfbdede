"""The setup step (idempotent, clear failures) and the README's main command."""
import json
import os
import sys

import pytest
from conftest import WORKSPACE

from swim_ros.processes import run_child

SETUP = WORKSPACE / "scripts" / "setup.sh"
#: a second setup only hashes its inputs against the last run's stamps: well under a second (README); 120 s only stops
#: a hung setup
SETUP_TIMEOUT_S = 120
#: a command that stops at its first check (a bad interpreter, a missing executable): a second or two; 60 s margin
EARLY_FAILURE_TIMEOUT_S = 60
#: swim-model-demo's 3 s runs of the model with its figures: under a minute here; 300 s for a loaded host
MODEL_DEMO_TIMEOUT_S = 300


def test_second_setup_does_no_work():
    result = run_child(["bash", str(SETUP)], capture_output=True, text=True, timeout_s=SETUP_TIMEOUT_S)
    assert result.returncode == 0, result.stderr
    assert "installing" not in result.stdout and "colcon build" not in result.stdout
    assert result.stdout.strip().endswith(f"ready ({WORKSPACE / '.venv'}, {WORKSPACE / 'install'})")


def test_setup_refuses_a_python_that_is_not_3_11(tmp_path):
    fake = tmp_path / "python3.12"
    # answers setup's version check as a Python 3.12 would: the check exits 1, the report prints 3.12
    fake.write_text('#!/bin/sh\ncase "$2" in *sys.exit*) exit 1;; *) echo 3.12;; esac\n')
    fake.chmod(0o755)
    env = dict(os.environ, SWIM_PYTHON=str(fake), SWIM_VENV=str(tmp_path / "venv"))
    result = run_child(["bash", str(SETUP)], capture_output=True, text=True, env=env,
                       timeout_s=EARLY_FAILURE_TIMEOUT_S)
    assert result.returncode != 0
    assert "not 3.11" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "venv").exists()


def test_ros2_run_stand_in_names_what_is_missing():
    result = run_child(["bash", "-c", "source scripts/env.sh && ros2 run swim_model no-such-tool"],
                       cwd=WORKSPACE, capture_output=True, text=True, timeout_s=EARLY_FAILURE_TIMEOUT_S)
    assert result.returncode == 1 and "no executable 'no-such-tool' in package 'swim_model'" in result.stderr


def test_setup_names_a_missing_python(tmp_path):
    env = dict(os.environ, SWIM_PYTHON="python-that-does-not-exist")
    result = run_child(["bash", str(SETUP)], capture_output=True, text=True, env=env,
                       timeout_s=EARLY_FAILURE_TIMEOUT_S)
    assert result.returncode != 0 and "no 'python-that-does-not-exist' on PATH" in result.stderr


def test_model_demo_runs_through_ros2_run(tmp_path):
    """`ros2 run swim_model swim-model-demo` (the README's demo) prints and saves what it claims."""
    from swim_model import VehicleModel
    command = f"source scripts/env.sh && exec ros2 run swim_model swim-model-demo --duration 3 --output-dir {tmp_path}"
    result = run_child(["bash", "-c", command], cwd=WORKSPACE, capture_output=True, text=True,
                       timeout_s=MODEL_DEMO_TIMEOUT_S)
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    added = VehicleModel(constrained=True).added_mass
    assert summary["added_mass_whole_span"]["m22"] == pytest.approx(added.m22, rel=1e-12)
    assert f"{added.m22:12.6e}" in result.stdout
    for run in summary["runs"].values():
        assert run["arc_length_m"] > 0.01  # pitch leads heave by 90 deg: it swims forward
    assert (tmp_path / "gait.png").stat().st_size > 20_000


def test_model_demo_reports_a_bad_rig_file_clearly(tmp_path):
    bad = tmp_path / "rig.yaml"
    bad.write_text("format_version: 1\nparameters: {}\n")
    result = run_child([sys.executable, "-m", "swim_model.demo", "--rig", str(bad), "--output-dir", str(tmp_path)],
                       capture_output=True, text=True, timeout_s=EARLY_FAILURE_TIMEOUT_S)
    assert result.returncode == 2
    assert "missing parameters" in result.stderr and "Traceback" not in result.stderr
