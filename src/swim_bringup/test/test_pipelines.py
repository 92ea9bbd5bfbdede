"""The two pipelines' parameter folders: installed, each parameter one its node declares with a value it accepts,
the paper's disturbance sizes exactly Disturbances.paper(), the two differing only in the flow, the sizes and the
tracker's range guard (the paper's law has none); and swim-demo choosing between them."""
import dataclasses
from pathlib import Path

import pytest
import yaml

from swim_bringup.system import PIPELINES, config_dir

SOURCE_CONFIG = Path(__file__).resolve().parents[1] / "config"
FILES = ("sim.yaml", "planner.yaml", "tracker.yaml", "bridge.yaml")
#: what each pipeline sets to tell itself from the other (every other parameter is the same in both)
PIPELINE_PARAMETERS = {("sim_node", "flow"), ("planner_node", "flow_model"), ("bridge_node", "flow"),
                       ("tracker_node", "range_guard_enabled")}


def flat_parameters(path: Path) -> dict[str, dict[str, object]]:
    """node name -> {parameter name: value} of a ROS parameter file, nested keys joined by '.' as rclpy does."""
    def flatten(mapping: dict, prefix: str = "") -> dict[str, object]:
        flat: dict[str, object] = {}
        for key, value in mapping.items():
            if isinstance(value, dict):
                flat.update(flatten(value, f"{prefix}{key}."))
            else:
                flat[f"{prefix}{key}"] = value
        return flat
    document = yaml.safe_load(path.read_text())
    return {node: flatten(body["ros__parameters"]) for node, body in document.items()}


def node_tables():
    """node name -> its parameter table (swim_ros.parameters.ParameterSpec by name)."""
    from swim_controller.tracker_node import PARAMETERS as TRACKER
    from swim_hw_bridge.bridge_node import PARAMETERS as BRIDGE
    from swim_planner.planner_node import PARAMETERS as PLANNER
    from swim_sim.sim_node import PARAMETERS as SIM
    return {node: {spec.name: spec for spec in table}
            for node, table in (("sim_node", SIM), ("planner_node", PLANNER), ("tracker_node", TRACKER),
                                ("bridge_node", BRIDGE))}


def test_config_dir_gives_each_pipelines_installed_folder():
    realistic, paper = config_dir("realistic"), config_dir("paper")
    assert PIPELINES == ("realistic", "paper") and config_dir() == realistic
    assert paper == realistic / "paper"
    for folder, source in ((realistic, SOURCE_CONFIG), (paper, SOURCE_CONFIG / "paper")):
        for name in FILES:
            assert (folder / name).read_text() == (source / name).read_text(), f"{folder / name} is not installed"
    with pytest.raises(ValueError, match="realistic, paper"):
        config_dir("ideal")


@pytest.mark.parametrize("pipeline", PIPELINES)
def test_every_parameter_is_declared_by_its_node_with_a_valid_value(pipeline):
    """A name no node declares would be ignored by ROS without a word (a realistic sim.yaml with flow: wake
    needs a sim_node that declares flow)."""
    tables = node_tables()
    for name in FILES:
        for node, parameters in flat_parameters(config_dir(pipeline) / name).items():
            for parameter, value in parameters.items():
                spec = tables[node].get(parameter)
                assert spec is not None, f"{pipeline} {name}: {node} declares no parameter {parameter}"
                assert type(value) is type(spec.default), f"{pipeline} {name}: {parameter} = {value!r}"
                assert spec.reason_invalid(value) is None, spec.reason_invalid(value)


def test_the_papers_sim_sets_exactly_the_papers_disturbance_sizes_and_ideal_flow():
    from swim_model.disturbances import Disturbances
    sim = flat_parameters(config_dir("paper") / "sim.yaml")["sim_node"]
    sizes = {name.split(".", 1)[1]: value for name, value in sim.items() if name.startswith("disturbances.")}
    assert Disturbances(**sizes) == Disturbances.paper()   # every field set (no default slips in), each exact
    assert sizes.keys() == {f.name for f in dataclasses.fields(Disturbances)}
    assert sim["flow"] == "ideal"
    assert flat_parameters(config_dir("paper") / "planner.yaml")["planner_node"]["flow_model"] == "ideal"
    assert not flat_parameters(config_dir("paper") / "tracker.yaml")["tracker_node"]["range_guard_enabled"]


def test_the_realistic_pipeline_flies_circulatory_plans_in_the_wake_under_the_physical_sizes():
    sim = flat_parameters(config_dir("realistic") / "sim.yaml")["sim_node"]
    assert sim["flow"] == "wake"
    assert not any(name.startswith("disturbances.") for name in sim)   # sim_node's defaults: the physical sizes
    assert flat_parameters(config_dir("realistic") / "planner.yaml")["planner_node"]["flow_model"] == "circulatory"
    tracker = flat_parameters(config_dir("realistic") / "tracker.yaml")["tracker_node"]
    assert tracker.get("range_guard_enabled", True)   # tracker_node's default: on


def test_the_pipelines_differ_only_in_the_flow_the_disturbance_sizes_and_the_range_guard():
    for name in FILES:
        realistic, paper = (flat_parameters(config_dir(p) / name) for p in PIPELINES)
        assert realistic.keys() == paper.keys()
        for node in realistic:
            def shared(parameters):
                return {k: v for k, v in parameters.items()
                        if (node, k) not in PIPELINE_PARAMETERS and not k.startswith("disturbances.")}
            assert shared(realistic[node]) == shared(paper[node]), f"{name}: {node}"


def test_swim_demo_runs_the_realistic_pipeline_on_either_plant_unless_told():
    from swim_bringup.demo import parameter_folder, parse_arguments
    assert parse_arguments([]).pipeline == "realistic"
    assert parameter_folder(parse_arguments([])) == config_dir("realistic")
    assert parameter_folder(parse_arguments(["--pipeline", "paper"])) == config_dir("paper")
    assert parameter_folder(parse_arguments(["--pipeline", "paper", "--config", "/x"])) == Path("/x")
    assert parse_arguments(["--plant", "bridge"]).pipeline == "realistic"
    assert parse_arguments(["--plant", "bridge", "--pipeline", "paper", "--primitives",
                            "free/cruise/R0.43/E0.05"]).pipeline == "paper"
    with pytest.raises(SystemExit):
        parse_arguments(["--pipeline", "ideal"])
