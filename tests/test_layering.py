"""The package graph, read from the sources: each package imports only the layers below its own.

    swim_model <- swim_control <- swim_ros <- {swim_planner, swim_controller, swim_sim, swim_hw_bridge}
               <- {swim_bringup, swim_viz}

A package may import any package of a lower layer, none of its own layer and none above. The four in the middle
(planner, tracker, simulator, bridge) meet only through swim_ros's messages and the layers under it, so each can be
read, tested and replaced without the others. swim_model and swim_control carry no ROS at all. Every import counts,
a function's included (the ast of each module, not what a run happens to execute), in every module a package
installs (src/<package>/<package>, its ``testing`` subpackage too); the tests under src/<package>/test are not read.
"""
from __future__ import annotations

import ast
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from conftest import WORKSPACE

#: the layers, lowest first
LAYERS: tuple[frozenset[str], ...] = (
    frozenset({"swim_model"}),
    frozenset({"swim_control"}),
    frozenset({"swim_ros"}),
    frozenset({"swim_planner", "swim_controller", "swim_sim", "swim_hw_bridge"}),
    frozenset({"swim_bringup", "swim_viz"}),
)
#: the packages that carry no ROS: nothing of a ROS install may be imported there
ROS_FREE = ("swim_model", "swim_control")
#: what a ROS install provides: rclpy and its tools, and generated interface packages (swim_interfaces among them)
ROS_MODULE = re.compile(r"^(rclpy|rosidl_\w+|ament_index_python|launch|launch_ros|rosbag2_py|\w+_msgs|\w+_srvs"
                        r"|\w+_interfaces)$")
#: the swim packages the layering orders (the interface packages, swim_interfaces and tf2_msgs, are ROS's)
LAYERED = frozenset().union(*LAYERS)


def layer_of(package: str) -> int:
    return next(index for index, layer in enumerate(LAYERS) if package in layer)


def imported_modules(source: str) -> set[str]:
    """The absolute module names a module's source imports, at any depth (functions, branches, try blocks), and
    those named to importlib.import_module as a constant."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None)) == \
                "import_module" and node.args and isinstance(node.args[0], ast.Constant) and \
                isinstance(node.args[0].value, str):
            names.add(node.args[0].value)
    return names


def package_imports(src: Path, package: str) -> dict[str, set[str]]:
    """{top-level module imported: the package's files (relative to src) that import it}, over the modules the
    package installs (src/<package>/<package>/**.py), its own name left out."""
    found: dict[str, set[str]] = {}
    for path in sorted((src / package / package).rglob("*.py")):
        for module in imported_modules(path.read_text()):
            top = module.split(".")[0]
            if top != package:
                found.setdefault(top, set()).add(str(path.relative_to(src)))
    return found


def layering_violations(src: Path) -> list[str]:
    """Each import of a swim package that is not in a lower layer than the importer's, as
    "importer -> imported (files)"."""
    violations = []
    for package in sorted(LAYERED):
        if not (src / package / package).is_dir():
            continue
        for imported, files in sorted(package_imports(src, package).items()):
            if imported in LAYERED and layer_of(imported) >= layer_of(package):
                violations.append(f"{package} -> {imported} ({', '.join(sorted(files))})")
    return violations


def test_the_source_tree_holds_every_layered_package():
    """The layers name every Python package under src (a new package must be placed in them), and only those."""
    python_packages = {path.parent.name for path in (WORKSPACE / "src").glob("*/setup.py")}
    assert python_packages == LAYERED


def test_each_package_imports_only_lower_layers():
    assert layering_violations(WORKSPACE / "src") == []


@pytest.mark.parametrize("package", ROS_FREE)
def test_the_core_packages_import_no_ros(package):
    ros = {module: sorted(files) for module, files in package_imports(WORKSPACE / "src", package).items()
           if ROS_MODULE.match(module)}
    assert ros == {}


@pytest.mark.parametrize("package", sorted(LAYERED))
def test_each_imported_swim_package_is_an_exec_depend(package):
    """colcon orders builds and rosdep installs by package.xml: a swim package imported but not declared would
    work only by the accident of a whole-workspace build."""
    manifest = ET.parse(WORKSPACE / "src" / package / "package.xml").getroot()
    declared = {element.text for element in manifest.iter("exec_depend")} | \
        {element.text for element in manifest.iter("depend")}
    imported = {module for module in package_imports(WORKSPACE / "src", package)
                if module.startswith("swim_") or module == "tf2_msgs"}
    assert imported - declared == set()


def write_package(src: Path, package: str, modules: dict[str, str]) -> None:
    for name, source in modules.items():
        path = src / package / package / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source)


def test_the_check_finds_an_upward_edge_an_edge_in_a_layer_and_a_function_level_import(tmp_path):
    """A tree with three wrong edges (swim_control importing swim_ros inside a function, the planner importing the
    tracker, the simulator importing the planner through importlib) and the right ones (downward, to swim_ros's
    interface package, to the standard library), and a test folder that may import anything."""
    write_package(tmp_path, "swim_model", {"__init__.py": "import math\n"})
    write_package(tmp_path, "swim_control", {
        "__init__.py": "",
        "trajectory.py": "from swim_model import vehicle\n\n\ndef encode():\n    from swim_ros.codecs import x\n"})
    write_package(tmp_path, "swim_ros", {"codecs.py": "import swim_control.trajectory\nimport swim_interfaces.msg\n"})
    write_package(tmp_path, "swim_planner", {"maneuver.py": "from swim_controller.tracker import CascadeTracker\n"})
    write_package(tmp_path, "swim_sim", {
        "sim_node.py": "import importlib\nplanner = importlib.import_module('swim_planner.maneuver')\n"})
    write_package(tmp_path, "swim_bringup", {"demo.py": "import swim_sim\nfrom swim_control import measures\n"})
    (tmp_path / "swim_ros" / "test").mkdir()
    (tmp_path / "swim_ros" / "test" / "test_codecs.py").write_text("import swim_bringup\n")
    assert layering_violations(tmp_path) == [
        "swim_control -> swim_ros (swim_control/swim_control/trajectory.py)",
        "swim_planner -> swim_controller (swim_planner/swim_planner/maneuver.py)",
        "swim_sim -> swim_planner (swim_sim/swim_sim/sim_node.py)",
    ]
