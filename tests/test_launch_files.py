"""swim_bringup's declarative launch files name only what exists: packages, executables, parameter files, parameters.

ROS 2's `launch` is not installable here, so the launch files (XML and YAML front ends of launch_ros) are read
with xml.etree and yaml, following launch_ros' Node.parse: `arg` (default), `node` (pkg, exec, name) and its
`param` entries (`from` a file, or `name` with a `value` or nested `param`s), substitutions $(find-pkg-share PKG)
and $(var NAME). Each node is then started for real (its installed executable, the launch file's parameter files
and parameters, over DDS in the test's domain) and asked for its parameters through the rcl_interfaces services:
the names it declares, and the values it took. Every parameter name the launch files and swim_bringup's config
YAMLs set must be one of those, and the values must be the ones set (a file keyed by another node name is
ignored by ROS without a word; this catches it). The negative cases misspell things in a temporary copy of the
installed share and check that each is reported.
"""
from __future__ import annotations

import dataclasses
import json
import re
import shutil
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Callable

import pytest
import yaml
from swim_ros.calls import RetryPolicy

from conftest import PACKAGES, WORKSPACE

INSTALL = WORKSPACE / "install"
SOURCE_LAUNCH_DIR = WORKSPACE / "src" / "swim_bringup" / "launch"
SUBSTITUTION = re.compile(r"\$\((\S+)\s+([^)]*)\)")
#: a launched node's start, its parameter services up and discovered: several s for a node that builds its models
#: at start on a loaded 2-core host, all of a launch file's nodes starting at once; 60 s margin
NODE_START_TIMEOUT_S = 60.0
#: the parameter services are idempotent, so a lost answer (one CI run lost sim_node's: "failed to send response
#: (timeout)" in its log) is asked again; a node that is up answers in milliseconds, a try waits 10 s
POLICY = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=NODE_START_TIMEOUT_S)


class LaunchFileError(ValueError):
    """Something this check cannot read: an unsupported action, attribute or substitution."""


@dataclasses.dataclass
class LaunchNode:
    source: str                           # launch file name
    package: str
    executable: str
    name: str
    params_files: list[Path]
    parameters: dict[str, object]         # inline, typed as launch_ros types them (YAML rules)

    @property
    def key(self) -> tuple:
        return (self.package, self.executable, self.name, tuple(map(str, self.params_files)),
                tuple(sorted((k, repr(v)) for k, v in self.parameters.items())))


def installed_share(package: str) -> Path:
    """$(find-pkg-share package) in this workspace's isolated install/ layout."""
    return INSTALL / package / "share" / package


# --- reading launch files (the subset of launch_ros' frontend we use, anything else refused) ----------------
def substitute(text: str, arguments: dict[str, str], share: Callable[[str], Path]) -> str:
    def replace(match: re.Match) -> str:
        kind, value = match.group(1), match.group(2).strip()
        if kind == "find-pkg-share":
            return str(share(value))
        if kind == "var":
            if value not in arguments:
                raise LaunchFileError(f"$(var {value}): no such arg")
            return arguments[value]
        raise LaunchFileError(f"substitution $({kind} ...) is not checked by this test")
    return SUBSTITUTION.sub(replace, text)


def typed(value: object, arguments: dict[str, str], share: Callable[[str], Path]) -> object:
    """A parameter value as launch_ros types it: strings (after substitution) by YAML rules."""
    return yaml.safe_load(substitute(value, arguments, share)) if isinstance(value, str) else value


def flatten_params(entries: list[dict], prefix: str = "") -> dict[str, object]:
    """`param` entries with name and value or nested params -> {dotted.name: raw value}."""
    flat = {}
    for entry in entries:
        name = prefix + entry["name"]
        if "param" in entry:
            flat.update(flatten_params(entry["param"], name + "."))
        else:
            flat[name] = entry["value"]
    return flat


def node_from_entries(source: str, attributes: dict, params: list[dict], arguments: dict[str, str],
                      share: Callable[[str], Path]) -> LaunchNode:
    unknown = set(attributes) - {"pkg", "exec", "name", "output", "param"}
    if unknown:
        raise LaunchFileError(f"{source}: node attributes {sorted(unknown)} are not checked by this test")
    files = [Path(substitute(p["from"], arguments, share)) for p in params if "from" in p]
    inline = flatten_params([p for p in params if "from" not in p])
    return LaunchNode(source, substitute(attributes["pkg"], arguments, share),
                      substitute(attributes["exec"], arguments, share),
                      substitute(attributes.get("name", attributes["exec"]), arguments, share), files,
                      {name: typed(value, arguments, share) for name, value in inline.items()})


def xml_params(element: ElementTree.Element) -> list[dict]:
    """<param> children as the YAML front end's dicts."""
    entries = []
    for child in element.findall("param"):
        entry = dict(child.attrib)
        if child.findall("param"):
            entry["param"] = xml_params(child)
        entries.append(entry)
    return entries


def read_xml(path: Path, share: Callable[[str], Path]) -> list[LaunchNode]:
    root = ElementTree.parse(path).getroot()
    if root.tag != "launch":
        raise LaunchFileError(f"{path.name}: the root element is <{root.tag}>, not <launch>")
    arguments, nodes = {}, []
    for element in root:
        if element.tag == "arg":
            arguments[element.attrib["name"]] = element.attrib.get("default", "")
        elif element.tag == "node":
            nodes.append(node_from_entries(path.name, {**element.attrib, "param": None}, xml_params(element),
                                           arguments, share))
        else:
            raise LaunchFileError(f"{path.name}: <{element.tag}> is not checked by this test")
    return nodes


def read_yaml(path: Path, share: Callable[[str], Path]) -> list[LaunchNode]:
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, dict) or list(document) != ["launch"]:
        raise LaunchFileError(f"{path.name}: the document is not one 'launch' list")
    arguments, nodes = {}, []
    for action in document["launch"]:
        (kind, body), = action.items()
        if kind == "arg":
            arguments[body["name"]] = str(body.get("default", ""))
        elif kind == "node":
            nodes.append(node_from_entries(path.name, body, body.get("param", []), arguments, share))
        else:
            raise LaunchFileError(f"{path.name}: '{kind}' is not checked by this test")
    return nodes


def read_launch_file(path: Path, share: Callable[[str], Path] = installed_share) -> list[LaunchNode]:
    return read_xml(path, share) if path.suffix == ".xml" else read_yaml(path, share)


def launch_files(share_dir: Path) -> list[Path]:
    return sorted((share_dir / "launch").glob("*.launch.*"))


# --- parameter files -------------------------------------------------------------------------------------------
def flatten(tree: dict, prefix: str = "") -> dict[str, object]:
    flat = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            flat.update(flatten(value, f"{prefix}{key}."))
        else:
            flat[prefix + key] = value
    return flat


def file_parameters(path: Path) -> dict[str, dict[str, object]]:
    """{node key: {dotted name: value}} of a ROS 2 parameter file."""
    document = yaml.safe_load(path.read_text()) or {}
    return {key: flatten(body.get("ros__parameters", {})) for key, body in document.items()}


def applies_to(key: str, node_name: str) -> bool:
    return key.lstrip("/") in (node_name, "**")


def expected_values(node: LaunchNode) -> dict[str, object]:
    """What the node should hold: its files in order, then its inline parameters (launch_ros' order)."""
    values = {}
    for path in node.params_files:
        for key, parameters in file_parameters(path).items():
            if applies_to(key, node.name):
                values.update(parameters)
    values.update(node.parameters)
    return values


# --- the check ----------------------------------------------------------------------------------------------------
def problems(share_dir: Path, declared: dict[tuple[str, str], set[str]]) -> list[str]:
    """Everything a launch file or config YAML in share_dir names that does not exist; [] when all is well."""
    found = []
    nodes = []
    for path in launch_files(share_dir):
        try:
            nodes += read_launch_file(path, lambda p: share_dir if p == "swim_bringup" else installed_share(p))
        except (LaunchFileError, KeyError, ElementTree.ParseError, yaml.YAMLError) as err:
            found.append(f"{path.name}: cannot be read: {err!r}")
    for node in nodes:
        found += node_problems(node, declared)
    found += config_problems(share_dir, nodes, declared)
    return found


def node_problems(node: LaunchNode, declared: dict[tuple[str, str], set[str]]) -> list[str]:
    where = f"{node.source}: {node.package}/{node.executable}"
    if node.package not in PACKAGES:
        return [f"{where}: package {node.package} is not one of ours"]
    if not (INSTALL / node.package / "share/ament_index/resource_index/packages" / node.package).is_file():
        return [f"{where}: package {node.package} is not installed (no ament index entry under install/)"]
    executable = INSTALL / node.package / "lib" / node.package / node.executable
    if not (executable.is_file() and executable.stat().st_mode & 0o111):
        return [f"{where}: no executable {executable.relative_to(WORKSPACE)}"]
    found = []
    names = declared[(node.package, node.executable)]
    for path in node.params_files:
        if not path.is_file():
            found.append(f"{where}: parameter file {path} does not exist")
            continue
        keys = file_parameters(path)
        if not any(applies_to(key, node.name) for key in keys):
            found.append(f"{where}: {path.name} has no parameters for a node named {node.name} (keys {list(keys)})")
    found += [f"{where}: parameter {name} is not declared by {node.executable}"
              for name in node.parameters if name not in names]
    return found


def config_problems(share_dir: Path, nodes: list[LaunchNode], declared: dict[tuple[str, str], set[str]]) -> list[str]:
    """Every parameter file in config/: each node it configures is launched, each name it sets is declared."""
    found = []
    for path in sorted((share_dir / "config").glob("*.yaml")):
        document = yaml.safe_load(path.read_text())
        if not (isinstance(document, dict) and all(isinstance(v, dict) and "ros__parameters" in v
                                                   for v in document.values())):
            continue   # not a ROS parameter file
        for key, parameters in file_parameters(path).items():
            targets = {(n.package, n.executable) for n in nodes if applies_to(key, n.name)}
            if not targets:
                found.append(f"config/{path.name}: no launch file starts a node named {key}")
            for target in sorted(targets & set(declared)):   # an executable that does not exist is reported above
                found += [f"config/{path.name}: parameter {name} is not declared by {target[1]}"
                          for name in parameters if name not in declared[target]]
    return found


# --- the nodes themselves ---------------------------------------------------------------------------------------
def installed_nodes() -> list[LaunchNode]:
    return [node for path in launch_files(installed_share("swim_bringup")) for node in read_launch_file(path)]


def node_parameters(context, node_name: str) -> dict[str, object]:
    """Every parameter the running node named node_name declares, with its value (rcl_interfaces services)."""
    import rclpy
    from rcl_interfaces.srv import ListParameters
    from rclpy.executors import SingleThreadedExecutor
    from swim_ros.calls import ParameterCalls, call_service
    client_node = rclpy.create_node("launch_file_check", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client_node)
    try:
        listing = client_node.create_client(ListParameters, f"/{node_name}/list_parameters")
        assert listing.wait_for_service(timeout_sec=NODE_START_TIMEOUT_S), f"{node_name} did not come up"
        names = list(call_service(executor, listing, ListParameters.Request(), POLICY).result.names)
        values = ParameterCalls(client_node, executor, node_name, POLICY).get(names)
    finally:
        executor.shutdown()
        client_node.destroy_node()
    return {name: plain(value) for name, value in zip(names, values)}


def plain(value: object) -> object:
    """Array parameters (array.array, numpy) as lists, to compare with YAML's."""
    return value if isinstance(value, (bool, int, float, str)) else list(value)


def parameter_argument(name: str, value: object) -> str:
    """`name:=value` for -p: the value as JSON, which is YAML, which is how ROS reads it."""
    return f"{name}:={json.dumps(value)}"


@pytest.fixture(scope="module")
def live_parameters(ros_domain, tmp_path_factory):
    """{LaunchNode key: {name: value}} of every node of every installed launch file, each started as its launch
    file says (one launch file at a time: both start a tracker_node)."""
    import rclpy
    from swim_bringup.system import System
    from swim_ros.processes import NodeSpec
    logs = tmp_path_factory.mktemp("launch_nodes")
    context = rclpy.Context()
    rclpy.init(context=context)
    found = {}
    try:
        for path in launch_files(installed_share("swim_bringup")):
            nodes = [n for n in read_launch_file(path) if n.key not in found]
            specs = [NodeSpec(n.package, n.executable,
                              parameters=tuple(parameter_argument(k, v) for k, v in n.parameters.items()),
                              ros_arguments=tuple(a for f in n.params_files for a in ("--params-file", str(f)))
                              + ("-r", f"__node:={n.name}")) for n in nodes]
            with System(specs, logs / path.name):
                for node in nodes:
                    found[node.key] = node_parameters(context, node.name)
    finally:
        rclpy.try_shutdown(context=context)
    return found


@pytest.fixture(scope="module")
def declared(live_parameters) -> dict[tuple[str, str], set[str]]:
    names: dict[tuple[str, str], set[str]] = {}
    for node in installed_nodes():
        names.setdefault((node.package, node.executable), set()).update(live_parameters[node.key])
    return names


# --- tests ----------------------------------------------------------------------------------------------------------
def test_every_launch_file_is_installed_as_written():
    sources = sorted(SOURCE_LAUNCH_DIR.glob("*.launch.*"))
    assert {p.suffix for p in sources} == {".xml", ".yaml"}   # both front ends are in use, so both are read
    for source in sources:
        assert (installed_share("swim_bringup") / "launch" / source.name).read_text() == source.read_text()
    assert [p.name for p in launch_files(installed_share("swim_bringup"))] == [p.name for p in sources]


def test_the_launch_files_start_the_closed_loop_on_either_plant():
    started = {path.name: {(n.package, n.executable) for n in read_launch_file(path)}
               for path in launch_files(installed_share("swim_bringup"))}
    loop = {("swim_planner", "planner_node"), ("swim_controller", "tracker_node"),
            ("swim_viz", "rig_state_publisher"), ("swim_viz", "marker_node")}
    assert started == {"bridge.launch.xml": loop | {("swim_hw_bridge", "bridge_node")},
                       "sim.launch.yaml": loop | {("swim_sim", "sim_node")}}


def test_everything_named_exists_and_every_parameter_is_declared(declared):
    assert problems(installed_share("swim_bringup"), declared) == []


def test_the_running_nodes_hold_the_values_set(live_parameters):
    for node in installed_nodes():
        held = live_parameters[node.key]
        expected = expected_values(node)
        assert expected, f"{node.name}: sets no parameters"
        assert {name: held.get(name) for name in expected} == expected, f"{node.source}: {node.name}"


# --- negative cases: each misspelling in a copy of the installed share is reported ---------------------------------
@pytest.fixture()
def share_copy(tmp_path):
    return Path(shutil.copytree(installed_share("swim_bringup"), tmp_path / "swim_bringup"))


def edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, f"{old!r} not in {path.name}"
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize("file, old, new, report", [
    ("launch/sim.launch.yaml", "exec: sim_node", "exec: sim_nod",
     "no executable install/swim_sim/lib/swim_sim/sim_nod"),
    ("launch/bridge.launch.xml", 'pkg="swim_hw_bridge"', 'pkg="swim_hw_brdge"', "swim_hw_brdge is not one of ours"),
    ("launch/bridge.launch.xml", 'name="sliding_mode_enabled"', 'name="sliding_mode_enable"',
     "parameter sliding_mode_enable is not declared by tracker_node"),
    ("launch/sim.launch.yaml", "config/planner.yaml", "config/planer.yaml", "planer.yaml does not exist"),
    ("config/tracker.yaml", "stale_after_periods:", "stale_after_period:",
     "config/tracker.yaml: parameter stale_after_period is not declared by tracker_node"),
    ("config/bridge.yaml", "watchdog_periods:", "watchdog_period:",
     "config/bridge.yaml: parameter watchdog_period is not declared by bridge_node"),
    ("config/sim.yaml", "sim_node:", "simulator:", "sim.yaml has no parameters for a node named sim_node"),
    ("launch/sim.launch.yaml", "$(var sliding_mode)", "$(var sliding)", "$(var sliding): no such arg"),
])
def test_a_misspelling_is_reported(share_copy, declared, file, old, new, report):
    assert problems(share_copy, declared) == []
    edit(share_copy / file, old, new)
    found = problems(share_copy, declared)
    assert any(report in line for line in found), found
