"""swim_bringup's declarative launch files name only what exists: packages, executables, parameter files, parameters.

ROS 2's `launch` is not installable here, so the launch files (XML and YAML front ends of launch_ros) are read
with xml.etree and yaml, following launch_ros' Node.parse: `arg` (default, or a value given as on the command
line), `node` (pkg, exec, name, an `if` or `unless` condition) and its `param` entries (`from` a file, or `name`
with a `value` or nested `param`s), substitutions $(find-pkg-share PKG) and $(var NAME). Each launch file is read
with its default arguments and with those of ARGUMENT_VARIANTS, so every node it can start is checked, and each
such set must be what swim-bringup starts for the same choices (swim_bringup.bringup.bringup_specs): the same
nodes, parameter files and parameters. Each node is then started for real (its installed executable, the launch
file's parameter files and parameters, over DDS in the test's domain) and asked for its parameters through the
rcl_interfaces services: the names it declares, and the values it took. Every parameter name the launch files
and swim_bringup's config YAMLs set must be one of those, and the values must be the ones set (a file keyed by
another node name is ignored by ROS without a word; this catches it). The negative cases misspell things in a
temporary copy of the installed share and check that each is reported.
"""
from __future__ import annotations

import dataclasses
import json
import re
import shutil
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Callable, Optional

import pytest
import yaml
from conftest import PACKAGES, WORKSPACE

from swim_ros.calls import RetryPolicy

INSTALL = WORKSPACE / "install"
SOURCE_LAUNCH_DIR = WORKSPACE / "src" / "swim_bringup" / "launch"
SUBSTITUTION = re.compile(r"\$\((\S+)\s+([^)]*)\)")
#: a launched node's start, its parameter services up and discovered: several s for a node that builds its models
#: at start on a loaded 2-core host, all of a launch file's nodes starting at once; 60 s margin
NODE_START_TIMEOUT_S = 60.0
#: the arguments each launch file is also read with, besides its defaults (`ros2 launch ... name:=value`), and
#: swim_bringup.bringup.bringup_specs' keywords for the same set; the defaults are bringup_specs(plant)
ARGUMENT_VARIANTS: dict[str, tuple[tuple[dict[str, str], dict[str, object]], ...]] = {
    "sim.launch.yaml": (({"realtime": "true"}, {"realtime": True}),
                        ({"sliding_mode": "false"}, {"sliding_mode": False})),
    "bridge.launch.xml": (({"backend": "mf624"}, {"backend": "mf624"}),
                          ({"sliding_mode": "false"}, {"sliding_mode": False})),
}
#: the plant each launch file starts, as swim-bringup names it
LAUNCH_FILE_PLANTS = {"sim.launch.yaml": "sim", "bridge.launch.xml": "bridge"}
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

    @property
    def names_key(self) -> tuple:
        """The key without the inline parameters' values: what a node started for real checks, once."""
        return (self.package, self.executable, self.name, tuple(map(str, self.params_files)),
                tuple(sorted(self.parameters)))


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


def condition_holds(source: str, attributes: dict, arguments: dict[str, str], share: Callable[[str], Path]) -> bool:
    """An action's `if` or `unless` as launch evaluates it: true or false (or 1 or 0) after substitution."""
    if "if" in attributes and "unless" in attributes:
        raise LaunchFileError(f"{source}: 'if' and 'unless' on one action")
    for key, holds_when in (("if", True), ("unless", False)):
        if key in attributes:
            value = substitute(str(attributes[key]), arguments, share).strip().lower()
            if value not in ("true", "false", "1", "0"):
                raise LaunchFileError(f"{source}: {key} {value!r} is not a boolean")
            return (value in ("true", "1")) == holds_when
    return True


def node_from_entries(source: str, attributes: dict, params: list[dict], arguments: dict[str, str],
                      share: Callable[[str], Path]) -> LaunchNode:
    unknown = set(attributes) - {"pkg", "exec", "name", "output", "param", "if", "unless"}
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


def unknown_given(path: Path, arguments: dict[str, str], given: dict[str, str]) -> None:
    unknown = set(given) - set(arguments)
    if unknown:
        raise LaunchFileError(f"{path.name}: no arg {sorted(unknown)}")


def read_xml(path: Path, share: Callable[[str], Path], given: dict[str, str]) -> list[LaunchNode]:
    root = ElementTree.parse(path).getroot()
    if root.tag != "launch":
        raise LaunchFileError(f"{path.name}: the root element is <{root.tag}>, not <launch>")
    arguments: dict[str, str] = {}
    nodes = []
    for element in root:
        if element.tag == "arg":
            name = element.attrib["name"]
            arguments[name] = given.get(name, element.attrib.get("default", ""))
        elif element.tag == "node":
            if condition_holds(path.name, element.attrib, arguments, share):
                nodes.append(node_from_entries(path.name, {**element.attrib, "param": None}, xml_params(element),
                                               arguments, share))
        else:
            raise LaunchFileError(f"{path.name}: <{element.tag}> is not checked by this test")
    unknown_given(path, arguments, given)
    return nodes


def read_yaml(path: Path, share: Callable[[str], Path], given: dict[str, str]) -> list[LaunchNode]:
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, dict) or list(document) != ["launch"]:
        raise LaunchFileError(f"{path.name}: the document is not one 'launch' list")
    arguments: dict[str, str] = {}
    nodes = []
    for action in document["launch"]:
        (kind, body), = action.items()
        if kind == "arg":
            arguments[body["name"]] = given.get(body["name"], str(body.get("default", "")))
        elif kind == "node":
            if condition_holds(path.name, body, arguments, share):
                nodes.append(node_from_entries(path.name, body, body.get("param", []), arguments, share))
        else:
            raise LaunchFileError(f"{path.name}: '{kind}' is not checked by this test")
    unknown_given(path, arguments, given)
    return nodes


def read_launch_file(path: Path, share: Callable[[str], Path] = installed_share,
                     given: Optional[dict[str, str]] = None) -> list[LaunchNode]:
    """The nodes the launch file starts with the arguments given (name: value, as `name:=value` on the command
    line), the others at their defaults."""
    reader = read_xml if path.suffix == ".xml" else read_yaml
    return reader(path, share, given or {})


def argument_sets(path: Path) -> list[dict[str, str]]:
    """The arguments a launch file is checked with: none given (its defaults), then ARGUMENT_VARIANTS'."""
    return [{}] + [given for given, _ in ARGUMENT_VARIANTS.get(path.name, ())]


def every_node(path: Path, share: Callable[[str], Path] = installed_share) -> list[LaunchNode]:
    """Each node the launch file starts with any of its argument_sets, once (by LaunchNode.key)."""
    nodes: dict[tuple, LaunchNode] = {}
    for given in argument_sets(path):
        for node in read_launch_file(path, share, given):
            nodes.setdefault(node.key, node)
    return list(nodes.values())


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
            nodes += every_node(path, lambda p: share_dir if p == "swim_bringup" else installed_share(p))
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
    return [node for path in launch_files(installed_share("swim_bringup")) for node in every_node(path)]


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
    """{LaunchNode key: {name: value}} of the nodes of every installed launch file and argument set, each started
    as its launch file says (one launch file and argument set at a time: each starts a tracker_node). A node that
    differs from one started only in an inline parameter's value (sliding_mode:=false, backend:=mf624) is not
    started again: its names are checked, and ROS types a value the same for every node."""
    import rclpy

    from swim_bringup.system import System
    from swim_ros.processes import NodeSpec
    logs = tmp_path_factory.mktemp("launch_nodes")
    context = rclpy.Context()
    rclpy.init(context=context)
    found = {}
    started = set()
    try:
        for path, given in [(p, g) for p in launch_files(installed_share("swim_bringup")) for g in argument_sets(p)]:
            nodes = [n for n in read_launch_file(path, given=given) if n.names_key not in started]
            if not nodes:
                continue
            # launch_ros' order: the files, then the inline parameters (the later of two values of a name wins)
            specs = [NodeSpec(n.package, n.executable,
                              ros_arguments=tuple(a for f in n.params_files for a in ("--params-file", str(f)))
                              + tuple(a for k, v in n.parameters.items() for a in ("-p", parameter_argument(k, v)))
                              + ("-r", f"__node:={n.name}")) for n in nodes]
            with System(specs, logs / f"{path.name}{''.join(f'-{k}-{v}' for k, v in given.items())}"):
                for node in nodes:
                    found[node.key] = node_parameters(context, node.name)
                    started.add(node.names_key)
    finally:
        rclpy.try_shutdown(context=context)
    return found


@pytest.fixture(scope="module")
def declared(live_parameters) -> dict[tuple[str, str], set[str]]:
    names: dict[tuple[str, str], set[str]] = {}
    for node in installed_nodes():
        names.setdefault((node.package, node.executable), set()).update(live_parameters.get(node.key, ()))
    return names


# --- tests ----------------------------------------------------------------------------------------------------------
def test_every_launch_file_is_installed_as_written():
    sources = sorted(SOURCE_LAUNCH_DIR.glob("*.launch.*"))
    assert {p.suffix for p in sources} == {".xml", ".yaml"}   # both front ends are in use, so both are read
    for source in sources:
        assert (installed_share("swim_bringup") / "launch" / source.name).read_text() == source.read_text()
    assert [p.name for p in launch_files(installed_share("swim_bringup"))] == [p.name for p in sources]


def test_the_launch_files_start_the_closed_loop_on_either_plant():
    loop = [("swim_planner", "planner_node"), ("swim_controller", "tracker_node"), ("swim_bringup", "maneuver_node"),
            ("swim_viz", "rig_state_publisher"), ("swim_viz", "marker_node")]
    plants = {"bridge.launch.xml": ("swim_hw_bridge", "bridge_node"), "sim.launch.yaml": ("swim_sim", "sim_node")}
    paths = launch_files(installed_share("swim_bringup"))
    assert [path.name for path in paths] == sorted(plants)
    for path in paths:
        for given in argument_sets(path):
            started = sorted((n.package, n.executable) for n in read_launch_file(path, given=given))
            assert started == sorted([plants[path.name], *loop]), f"{path.name} {given}"


def started_by_launch_file(nodes: list[LaunchNode]) -> set[tuple]:
    """(package, executable, node name, parameter files, inline parameters) of each node, the files resolved."""
    return {(n.package, n.executable, n.name, tuple(f.resolve() for f in n.params_files),
             tuple(sorted((name, repr(value)) for name, value in n.parameters.items()))) for n in nodes}


def started_by_swim_bringup(specs) -> set[tuple]:
    """The same of NodeSpecs: their `name:=value` overrides typed as ROS types them (YAML), the node named for its
    executable (swim-bringup renames none)."""
    def typed_override(override: str) -> tuple[str, str]:
        name, _, value = override.partition(":=")
        return name, repr(yaml.safe_load(value))
    assert all(not spec.ros_arguments for spec in specs)
    return {(s.package, s.executable, s.executable, () if s.params_file is None else (s.params_file.resolve(),),
             tuple(sorted(typed_override(o) for o in s.parameters))) for s in specs}


def test_swim_bringup_starts_what_the_launch_files_start():
    """Each launch file with each argument set against swim-bringup with the same choices: the same nodes with the
    same parameter files and parameters."""
    from swim_bringup.bringup import bringup_specs
    for path in launch_files(installed_share("swim_bringup")):
        plant = LAUNCH_FILE_PLANTS[path.name]
        for given, keywords in [({}, {}), *ARGUMENT_VARIANTS.get(path.name, ())]:
            launched = started_by_launch_file(read_launch_file(path, given=given))
            assert launched == started_by_swim_bringup(bringup_specs(plant, **keywords)), f"{path.name} {given}"


def test_everything_named_exists_and_every_parameter_is_declared(declared):
    assert problems(installed_share("swim_bringup"), declared) == []


def test_the_running_nodes_hold_the_values_set(live_parameters):
    for node in [n for n in installed_nodes() if n.key in live_parameters]:
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
    ("launch/sim.launch.yaml", "if: $(var realtime)", "if: $(var realtme)", "$(var realtme): no such arg"),
    ("config/maneuver.yaml", "rest_angular_speed_rad_s:", "rest_angular_speed:",
     "config/maneuver.yaml: parameter rest_angular_speed is not declared by maneuver_node"),
])
def test_a_misspelling_is_reported(share_copy, declared, file, old, new, report):
    assert problems(share_copy, declared) == []
    edit(share_copy / file, old, new)
    found = problems(share_copy, declared)
    assert any(report in line for line in found), found
