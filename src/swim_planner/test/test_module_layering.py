"""What serves plans does not load the optimizer: the library, graph, maneuvers, gains and planner_node import
the primitives' data model (swim_planner.primitives), never the NLP (swim_planner.primitive_solver)."""
import sys

from swim_ros.processes import run_child

SERVING_MODULES = ("swim_planner.library", "swim_planner.graph", "swim_planner.maneuver", "swim_planner.gains",
                   "swim_planner.catalog", "swim_planner.planner_node")


def test_serving_modules_do_not_import_the_solver():
    script = (f"import sys\nfor name in {SERVING_MODULES!r}:\n    __import__(name)\n"
              "print('swim_planner.primitive_solver' in sys.modules)")
    result = run_child([sys.executable, "-c", script], capture_output=True, text=True, timeout_s=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"
