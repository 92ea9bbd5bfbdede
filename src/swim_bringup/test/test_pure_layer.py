"""The layer under swim-analyze and swim-experiments imports no ROS client library and no plotting: a fresh
interpreter that imports it has neither rclpy nor matplotlib loaded (its figures and command lines are the fronts'
modules: figures, wake_figure, analysis_cli, experiments_cli)."""
import json
import subprocess
import sys

PURE_MODULES = ("swim_bringup.run_record", "swim_bringup.analysis", "swim_bringup.experiments",
                "swim_bringup.reports", "swim_bringup.statistics", "swim_bringup.bag")
#: what the pure layer must not load: the ROS client library, plotting, the fronts' argument parsing and processes
FORBIDDEN = ("rclpy", "matplotlib", "swim_bringup.figures", "swim_bringup.analysis_cli",
             "swim_bringup.experiments_cli", "swim_bringup.recorded_run", "swim_bringup.run_client")


def test_the_pure_layer_loads_no_ros_and_no_plotting():
    program = (f"import importlib, json, sys\nfor name in {PURE_MODULES!r}: importlib.import_module(name)\n"
               f"print(json.dumps([name for name in {FORBIDDEN!r} if name in sys.modules]))")
    loaded = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(loaded.stdout) == []
