"""swim-demo: the paper's constrained maneuver in closed loop in simulation, recorded and analysed.

Brings up sim_node (lock-step), planner_node and tracker_node as separate processes over DDS with the parameter
files of a pipeline (swim_bringup.system.PIPELINES): "realistic", the circulatory flow model's plans in the vortex
wake under the physical disturbances, or "paper", the ideal-flow plans in ideal flow under the small disturbances
they survive (--config: a folder of one's own). It asks the planner for the maneuver, has the tracker
execute it while every topic of the run is recorded to an MCAP bag, stops the nodes, and writes report.json,
figures and the bag into the run folder; prints a summary naming the pipeline.
With --plant bridge, bridge_node (emulated backend, autostart) stands in for sim_node: the emulated rig is the
free vehicle in real time, so the default maneuver is then the paper's lane keeping. The default pipeline is the
realistic one on either plant. The run itself is recorded_run's; this module is its command line.
"""
from __future__ import annotations

import argparse
import datetime
import sys
from pathlib import Path

from swim_bringup.analysis import summary_table
from swim_bringup.experiments import PAPER_CONSTRAINED, PAPER_LANE_KEEPING
from swim_bringup.recorded_run import parse_with_tolerances, run_recorded
from swim_bringup.reports import run_failures
from swim_bringup.run_client import RunError
from swim_bringup.system import PIPELINES, PLANTS, closed_loop_specs, config_dir
from swim_ros.processes import interrupt_on_sigterm


def parse_arguments(argv: list[str] | None) -> argparse.Namespace:
    """The command line of swim-demo, parsed."""
    parser = argparse.ArgumentParser(prog="swim-demo", description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", type=Path, default=None, help="output folder (default runs/demo-<time>)")
    parser.add_argument("--plant", choices=tuple(PLANTS), default="sim",
                        help="sim: sim_node in lock-step; bridge: bridge_node, emulated free vehicle, real time")
    parser.add_argument("--primitives", nargs="+", default=None,
                        help="default: the paper's constrained maneuver (sim) or lane keeping (bridge)")
    parser.add_argument("--repeats", nargs="+", type=int, default=None)
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--sliding-mode", choices=("on", "off"), default="on")
    parser.add_argument("--pipeline", choices=PIPELINES, default="realistic",
                        help="realistic (the default): circulatory plans, vortex-wake plant, physical disturbances; "
                             "paper: ideal-flow plans and plant, the paper's small disturbances")
    parser.add_argument("--config", type=Path, default=None,
                        help="folder of sim/planner/tracker YAML files (default: the pipeline's)")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-time limit of the maneuver, s")
    parser.add_argument("--rig", default="", help="rig file every node loads (rig_path) and the analysis's hard "
                        "stops (default: swim_model's shipped rig)")
    args = parse_with_tolerances(parser, argv)
    default = PAPER_LANE_KEEPING if args.plant == "bridge" else PAPER_CONSTRAINED
    if args.primitives is None:
        args.primitives, args.repeats = default[0], args.repeats or default[1]
    if args.repeats is None:
        args.repeats = [1] * len(args.primitives)
    if args.plant == "bridge" and any(p.startswith("constrained/") for p in args.primitives):
        parser.error("the bridge's emulated rig is the free vehicle: choose free/... primitives")
    return args


def parameter_folder(args: argparse.Namespace) -> Path:
    """The folder of the run's parameter files: --config, else the pipeline's (swim_bringup.system.config_dir)."""
    return args.config or config_dir(args.pipeline)


def main(argv: list[str] | None = None) -> int:
    """The swim-demo command: one closed-loop run recorded and analysed; its exit status."""
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    args = parse_arguments(argv)
    run_dir = args.run_dir or Path("runs") / datetime.datetime.now().strftime("demo-%Y%m%d-%H%M%S")
    run_dir.mkdir(parents=True, exist_ok=True)
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    bag_path = run_dir / "bag"
    if bag_path.exists():
        print(f"swim-demo: {bag_path} exists; choose another --run-dir", file=sys.stderr)
        return 2
    from tqdm import tqdm
    config = parameter_folder(args)
    specs = closed_loop_specs(config,
                              tracker_overrides=(f"sliding_mode_enabled:={args.sliding_mode == 'on'}".lower(),),
                              plant=args.plant, rig_path=args.rig)
    print(f"swim-demo: bringing up {', '.join(s.executable for s in specs)} (logs in {run_dir / 'logs'})")
    try:
        with tqdm(total=100, unit="%", desc="maneuver", file=sys.stderr) as bar:
            report = run_recorded(specs, run_dir, args.primitives, args.repeats, args.time_scale, args.timeout,
                                  args.tolerances, lambda fraction: bar.update(round(100 * fraction) - bar.n),
                                  args.rig)
    except RunError as err:
        print(f"swim-demo: {err}", file=sys.stderr)
        return 1
    pipeline = f"the {args.pipeline} pipeline" if args.config is None else "parameter files of --config"
    print(f"swim-demo: {pipeline} ({config})")
    print(summary_table({run_dir.name: report}))
    print(f"swim-demo: report, figures and bag in {run_dir}")
    failures = run_failures(report)
    for failure in failures:
        print(f"swim-demo: {failure}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
