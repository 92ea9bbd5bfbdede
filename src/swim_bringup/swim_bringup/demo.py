"""swim-demo: the paper's constrained maneuver in closed loop in simulation, recorded and analysed.

Brings up sim_node (lock-step, default disturbances), planner_node and tracker_node as separate processes over
DDS, asks the planner for the maneuver, has the tracker execute it while every topic of the run is recorded to an
MCAP bag, stops the nodes, and writes report.json, figures and the bag into the run folder; prints a summary.
With --plant bridge, bridge_node (emulated backend, autostart) stands in for sim_node: the emulated rig is the
free vehicle in real time, so the default maneuver is then the paper's lane keeping.
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import sys
import time
from pathlib import Path

from swim_bringup.analysis import analyze, summary_table, write_figures
from swim_bringup.run_client import STARTUP_TIMEOUT_S, RunClient, RunError
from swim_bringup.system import PLANTS, NodeSpec, System, closed_loop_specs, config_dir
from swim_controller.supervisor import Tolerances

#: the paper's constrained maneuver (Sec. 7.1): accelerate to E1, cruise x2, cruise-to-cruise, cruise x2, stop
PAPER_CONSTRAINED = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05",
                      "constrained/cruise_to_cruise/E0.05-E0.10", "constrained/cruise/E0.10",
                      "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])
#: the paper's free lane keeping (Sec. 7.2) at R = 0.43 m: accelerate, 14 cruises, decelerate (20 s); the default
#: on the bridge, whose emulated rig is the free vehicle
PAPER_LANE_KEEPING = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
                      [1, 14, 1])
#: what the tracker checks on every run (0: not checked), so that a vehicle that lost its plan is not reported
#: as a success. All assumed: a vehicle a radian behind or ahead of its plan (43 cm of hub travel at R = 0.43 m)
#: is lost; at the end, within 0.25 rad (11 cm of travel; the slowed constrained maneuver at lambda = 0.8 ends
#: 0.16 rad behind) and nearer its lane than the next one (lanes 5 cm apart, Fig. 12: 2.5 cm)
RUN_TOLERANCES = Tolerances(path_alpha_rad=1.0, path_r_m=0.0, goal_alpha_rad=0.25, goal_r_m=0.025)
#: the name callers know for a run that could not be done
DemoError = RunError


def run_maneuver(bag_path: Path, primitive_ids: list[str], repeat_counts: list[int], time_scale: float,
                 timeout_s: float, progress=None, tolerances: Tolerances = RUN_TOLERANCES) -> dict:
    """Request the maneuver, execute it, record the run; returns the action's result as a dict."""
    with RunClient(bag_path) as client:
        client.wait_for_nodes(STARTUP_TIMEOUT_S)
        handle = client.execute(client.request(primitive_ids, repeat_counts, time_scale), progress, tolerances)
        result = client.result(handle, timeout_s)
        try:
            client.drain(result.duration_s)
        except RunError as err:   # name how the goal ended: a goal lost at its start leaves nothing to drain
            raise RunError(f"{err}; the goal ended after {result.duration_s:.3f} s with code {result.error_code}: "
                           f"{result.error_string}") from err
        return {"error_code": result.error_code, "error_string": result.error_string,
                "final_alpha_error_rad": result.final_alpha_error_rad, "duration_s": result.duration_s}


def run_recorded(specs: list[NodeSpec], run_dir: Path, primitive_ids: list[str], repeat_counts: list[int],
                 time_scale: float, timeout_s: float, tolerances: Tolerances = RUN_TOLERANCES,
                 progress=None) -> dict:
    """One closed-loop run: bring up the nodes of specs (logs in run_dir/logs), run the maneuver recorded into
    run_dir/bag, stop the nodes; then analyse the bag and write report.json and the figures into run_dir.
    Returns the report: the analysis measures, the action's result and the wall time. DemoError if a node died
    or the run could not be done."""
    started = time.monotonic()
    with System(specs, run_dir / "logs") as system:
        def on_progress(fraction: float) -> None:
            if progress is not None:
                progress(fraction)
            if system.dead():
                raise DemoError(f"{', '.join(system.dead())} died (see {run_dir / 'logs'})")
        result = run_maneuver(run_dir / "bag", primitive_ids, repeat_counts, time_scale, timeout_s, on_progress,
                              tolerances)
    report = analyze(run_dir / "bag")
    report["result"] = result
    report["wall_time_s"] = time.monotonic() - started
    (run_dir / "report.json").write_text(json.dumps(report, indent=2))
    write_figures(run_dir / "bag", run_dir)
    return report


def run_failures(report: dict) -> list[str]:
    """Why a run's report is not a success (empty if it is): the tracker's result, the bridge's latched faults."""
    failures = []
    if report["result"]["error_code"] != 0:
        failures.append(f"the tracker ended with {report['result']['error_string'] or report['result']['error_code']}")
    if report.get("bridge_faults", "NONE") != "NONE":
        failures.append(f"the bridge latched {report['bridge_faults']}: the motors were off from then on")
    return failures


def add_tolerance_arguments(parser: argparse.ArgumentParser) -> None:
    """The tracker's tolerances as options (defaults: RUN_TOLERANCES; 0 switches one off)."""
    for option, field, unit in (("--path-tolerance-alpha", "path_alpha_rad", "rad"),
                                ("--path-tolerance-r", "path_r_m", "m"),
                                ("--goal-tolerance-alpha", "goal_alpha_rad", "rad"),
                                ("--goal-tolerance-r", "goal_r_m", "m")):
        parser.add_argument(option, dest=field, type=float, default=getattr(RUN_TOLERANCES, field),
                            help=f"tracker tolerance, {unit} (0: not checked; default %(default)s)")


def parse_with_tolerances(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """parser's arguments plus the tolerance options; args.tolerances is the Tolerances they name (a negative or
    non-finite one is a usage error)."""
    add_tolerance_arguments(parser)
    args = parser.parse_args(argv)
    try:
        args.tolerances = Tolerances(**{field.name: getattr(args, field.name)
                                        for field in dataclasses.fields(Tolerances)})
        args.tolerances.validate()
    except ValueError as err:
        parser.error(str(err))
    return args


def parse_arguments(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="swim-demo", description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", type=Path, default=None, help="output folder (default runs/demo-<time>)")
    parser.add_argument("--plant", choices=tuple(PLANTS), default="sim",
                        help="sim: sim_node in lock-step; bridge: bridge_node, emulated free vehicle, real time")
    parser.add_argument("--primitives", nargs="+", default=None,
                        help="default: the paper's constrained maneuver (sim) or lane keeping (bridge)")
    parser.add_argument("--repeats", nargs="+", type=int, default=None)
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--sliding-mode", choices=("on", "off"), default="on")
    parser.add_argument("--config", type=Path, default=None, help="folder of sim/planner/tracker YAML files")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-time limit of the maneuver, s")
    args = parse_with_tolerances(parser, argv)
    default = PAPER_LANE_KEEPING if args.plant == "bridge" else PAPER_CONSTRAINED
    if args.primitives is None:
        args.primitives, args.repeats = default[0], args.repeats or default[1]
    if args.repeats is None:
        args.repeats = [1] * len(args.primitives)
    if args.plant == "bridge" and any(p.startswith("constrained/") for p in args.primitives):
        parser.error("the bridge's emulated rig is the free vehicle: choose free/... primitives")
    return args


def main(argv: list[str] | None = None) -> int:
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
    specs = closed_loop_specs(args.config or config_dir(),
                              tracker_overrides=(f"sliding_mode_enabled:={args.sliding_mode == 'on'}".lower(),),
                              plant=args.plant)
    print(f"swim-demo: bringing up {', '.join(s.executable for s in specs)} (logs in {run_dir / 'logs'})")
    try:
        with tqdm(total=100, unit="%", desc="maneuver", file=sys.stderr) as bar:
            report = run_recorded(specs, run_dir, args.primitives, args.repeats, args.time_scale, args.timeout,
                                  args.tolerances, lambda fraction: bar.update(round(100 * fraction) - bar.n))
    except DemoError as err:
        print(f"swim-demo: {err}", file=sys.stderr)
        return 1
    print(summary_table({run_dir.name: report}))
    print(f"swim-demo: report, figures and bag in {run_dir}")
    failures = run_failures(report)
    for failure in failures:
        print(f"swim-demo: {failure}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
