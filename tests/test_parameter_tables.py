"""Each node's parameter table in its package README is the node's ParameterSpec table rendered
(swim_ros.parameters.markdown_table), between ``<!-- parameters: MODULE:TABLE -->`` and ``<!-- end parameters -->``:
the README cannot drift from what the node declares. ``python tests/test_parameter_tables.py`` rewrites them."""
from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

WORKSPACE = Path(__file__).resolve().parent.parent
#: a README's generated table: the marker names the table (module and attribute) it is rendered from
GENERATED = re.compile(r"(<!-- parameters: (?P<module>[\w.]+):(?P<table>\w+) -->\n)(?P<body>.*?)"
                       r"(<!-- end parameters -->)", re.DOTALL)
#: every node's table: the README it is documented in and the settings type it is read as
NODE_TABLES = {
    "swim_controller.tracker_node:PARAMETERS": ("swim_controller", "TrackerSettings"),
    "swim_planner.planner_node:PARAMETERS": ("swim_planner", "PlannerSettings"),
    "swim_sim.sim_node:PARAMETERS": ("swim_sim", "SimSettings"),
    "swim_hw_bridge.bridge_node:PARAMETERS": ("swim_hw_bridge", "BridgeSettings"),
    "swim_bringup.maneuver_node:PARAMETERS": ("swim_bringup", "ManeuverSettings"),
    "swim_viz.rig_state_publisher:NODE_PARAMETERS": ("swim_viz", "RigStateSettings"),
    "swim_viz.marker_node:NODE_PARAMETERS": ("swim_viz", "MarkerSettings"),
    "swim_viz.foxglove_node:PARAMETERS": ("swim_viz", "FoxgloveSettings"),
}
PACKAGES = sorted({package for package, _ in NODE_TABLES.values()})


def rendered(readme_text: str) -> str:
    """readme_text with each generated table rendered from its node's table now."""
    from swim_ros.parameters import markdown_table

    def render(match: re.Match[str]) -> str:
        table = getattr(importlib.import_module(match["module"]), match["table"])
        return f"{match.group(1)}\n{markdown_table(table)}\n{match.group(5)}"
    return GENERATED.sub(render, readme_text)


def readme(package: str) -> Path:
    return WORKSPACE / "src" / package / "README.md"


def test_every_node_table_is_in_its_package_readme():
    found = {package: {f"{m['module']}:{m['table']}" for m in GENERATED.finditer(readme(package).read_text())}
             for package in PACKAGES}
    missing = [name for name, (package, _) in NODE_TABLES.items() if name not in found[package]]
    assert missing == [], f"README tables missing: {missing} (add the marker, then run {__file__})"


def test_the_readme_tables_are_the_node_tables():
    stale = [package for package in PACKAGES
             if rendered(readme(package).read_text()) != readme(package).read_text()]
    assert stale == [], f"README parameter tables differ from the nodes' tables in {stale}: run python {__file__}"


def test_every_settings_type_holds_its_table():
    """Each node's settings type has a field per parameter of its table, typed as its default (the nodes check
    the same when they start: swim_ros.parameters.NodeSettings)."""
    from swim_ros.parameters import check_settings_type
    for name, (_, settings_name) in NODE_TABLES.items():
        module_name, table_name = name.split(":")
        module = importlib.import_module(module_name)
        check_settings_type(getattr(module, settings_name), getattr(module, table_name))


def test_no_node_reads_a_parameter_but_through_its_settings():
    """The nodes read their NodeSettings snapshot's fields (swim_ros.parameters), never get_parameter."""
    readers = [name for name in NODE_TABLES if "get_parameter(" in
               Path(importlib.import_module(name.split(":")[0]).__file__ or "").read_text()]
    assert readers == []


def test_a_row_that_drifts_from_its_table_is_rendered_back():
    text = readme("swim_controller").read_text()
    drifted = text.replace("| `sample_period_s` | `0.008` | [0.001, 0.1] | no |",
                           "| `sample_period_s` | `0.008` | [0.001, 0.1] | yes |")
    assert drifted != text and rendered(drifted) == text


if __name__ == "__main__":
    for package in PACKAGES:
        path = readme(package)
        path.write_text(rendered(path.read_text()))
        print(f"wrote {path}", file=sys.stderr)
