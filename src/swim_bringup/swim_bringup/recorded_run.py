"""One closed-loop run over DDS, recorded and analysed: what swim-demo and swim-experiments each do per run.

run_recorded brings up the nodes (system.System), requests and executes the maneuver while the run's topics are
recorded to a bag (run_client.RunClient), stops the nodes, and writes report.json (reports.RunReport) and the
figures. The tracker's tolerances of a run default to RUN_TOLERANCES; add_tolerance_arguments and
parse_with_tolerances give a CLI the options for them (tolerances_of reads them from a parser of subcommands).
write_run_report reads a recorded run's bag once (run_record.read_bag), analyses it (analysis.run_analysis) and
writes its report and figures (figures.write_run_figures): run_recorded's last step, and swim-maneuver's after a
run it recorded.
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path
from typing import Callable, Optional, Sequence

from swim_bringup.analysis import rig_hard_limits, run_analysis
from swim_bringup.figures import write_run_figures
from swim_bringup.reports import RunReport, TrackerResult
from swim_bringup.run_client import STARTUP_TIMEOUT_S, NodeDied, RunClient, RunError
from swim_bringup.run_record import read_bag
from swim_bringup.system import System
from swim_controller.supervisor import Tolerances
from swim_ros.processes import NodeSpec

#: what the tracker checks on every run (0: not checked), so that a vehicle that lost its plan is not reported
#: as a success. All assumed: a vehicle a radian behind or ahead of its plan (43 cm of hub travel at R = 0.43 m)
#: is lost; at the end, within 0.25 rad (11 cm of travel; the slowed constrained maneuver at lambda = 0.8 ends
#: 0.16 rad behind) and nearer its lane than the next one (lanes 5 cm apart, Fig. 12: 2.5 cm)
RUN_TOLERANCES = Tolerances(path_alpha_rad=1.0, path_r_m=0.0, goal_alpha_rad=0.25, goal_r_m=0.025)

Progress = Callable[[float], None]   # called with the fraction of the plan done, 0 to 1


def run_maneuver(bag_path: Path, primitive_ids: list[str], repeat_counts: list[int], time_scale: float,
                 timeout_s: float, progress: Optional[Progress] = None,
                 tolerances: Tolerances = RUN_TOLERANCES, first_messages: Sequence[str] = ()) -> TrackerResult:
    """Request the maneuver, execute it and record the run; the tracker's result.

    Request the maneuver, execute it, record the run into the bag at bag_path; the tracker's result. The request
    waits for the loop (RunClient.wait_for_nodes) and for a first message on each of first_messages. RunError
    if the run could not be done.
    """
    with RunClient(bag_path) as client:
        client.wait_for_nodes(STARTUP_TIMEOUT_S, first_messages)
        handle = client.execute(client.request(primitive_ids, repeat_counts, time_scale), progress, tolerances)
        result = client.result(handle, timeout_s)
        try:
            client.drain(result.duration_s)
        except RunError as err:   # name how the goal ended: a goal lost at its start leaves nothing to drain
            raise RunError(f"{err}; the goal ended after {result.duration_s:.3f} s with code {result.error_code}: "
                           f"{result.error_string}") from err
        return TrackerResult(error_code=result.error_code, error_string=result.error_string,
                             final_alpha_error_rad=result.final_alpha_error_rad, duration_s=result.duration_s)


#: what a node publishes while the loop idles, by executable: a run with the node waits for its first message, so
#: that the bag holds it from the maneuver's start (a short lock-step run can end before discovery delivers it)
IDLE_PUBLICATIONS = {"rig_state_publisher": ("/tf",)}


def idle_topics_of(specs: Sequence[NodeSpec]) -> tuple[str, ...]:
    """The topics IDLE_PUBLICATIONS names for the nodes of specs."""
    return tuple(topic for spec in specs for topic in IDLE_PUBLICATIONS.get(spec.executable, ()))


def run_recorded(specs: list[NodeSpec], run_dir: Path, primitive_ids: list[str], repeat_counts: list[int],
                 time_scale: float, timeout_s: float, tolerances: Tolerances = RUN_TOLERANCES,
                 progress: Optional[Progress] = None, rig_path: str = "") -> RunReport:
    """One closed-loop run, recorded and analysed; its report.

    One closed-loop run: bring up the nodes of specs (logs in run_dir/logs), run the maneuver recorded into
    run_dir/bag, stop the nodes; then analyse the bag (the hard stops of the rig file at rig_path, empty: the
    shipped rig, as the nodes' rig_path) and write report.json and the figures into run_dir.
    Returns the report: the analysis measures, the tracker's result and the wall time. RunError if a node died
    or the run could not be done.
    """
    started = time.monotonic()
    with System(specs, run_dir / "logs") as system:
        def on_progress(fraction: float) -> None:
            if progress is not None:
                progress(fraction)
            if system.dead():
                raise NodeDied(system.dead(), run_dir / "logs")
        try:
            result = run_maneuver(run_dir / "bag", primitive_ids, repeat_counts, time_scale, timeout_s, on_progress,
                                  tolerances, idle_topics_of(specs))
        except NodeDied:
            raise
        except RunError as err:   # a node that died meanwhile is what the reader needs to know first
            dead = system.dead()
            if dead:
                raise NodeDied(dead, run_dir / "logs", str(err)) from err
            raise
        dead = system.dead()   # a dead simulator ends the goal (STATE_LOST), a dead tracker its feedback
        if dead:
            raise NodeDied(dead, run_dir / "logs", f"the goal ended after {result.duration_s:.3f} s with code "
                                                   f"{result.error_code}: {result.error_string}")
    return write_run_report(run_dir, result, started, rig_path)


def write_run_report(run_dir: Path, result: TrackerResult, started_s: float, rig_path: str = "") -> RunReport:
    """Read and analyse the run's bag, write report.json and the figures; the report.

    Read the run's bag (run_dir/bag) once, analyse it (the hard stops of the rig file at rig_path, empty: the
    shipped rig) and write report.json and the figures into run_dir; the report, with the tracker's result and the
    wall time from started_s (time.monotonic) to now. MissingTopic (run_record) if the bag holds no tracked period.
    """
    record = read_bag(run_dir / "bag")
    analysis = run_analysis(record, rig_hard_limits(Path(rig_path) if rig_path else None))
    report = RunReport(analysis.measures, analysis.bridge, result, time.monotonic() - started_s)
    report.write(run_dir / "report.json")
    write_run_figures(record, run_dir)
    return report


def add_tolerance_arguments(parser: argparse.ArgumentParser) -> None:
    """The tracker's tolerances as options (defaults: RUN_TOLERANCES; 0 switches one off)."""
    for option, field, unit in (("--path-tolerance-alpha", "path_alpha_rad", "rad"),
                                ("--path-tolerance-r", "path_r_m", "m"),
                                ("--goal-tolerance-alpha", "goal_alpha_rad", "rad"),
                                ("--goal-tolerance-r", "goal_r_m", "m")):
        parser.add_argument(option, dest=field, type=float, default=getattr(RUN_TOLERANCES, field),
                            help=f"tracker tolerance, {unit} (0: not checked; default %(default)s)")


def parse_with_tolerances(parser: argparse.ArgumentParser, argv: Optional[list[str]]) -> argparse.Namespace:
    """Parse the arguments with the tolerance options.

    parser's arguments plus the tolerance options; args.tolerances is the Tolerances they name (a negative or
    non-finite one is a usage error).
    """
    add_tolerance_arguments(parser)
    args = parser.parse_args(argv)
    try:
        args.tolerances = tolerances_of(args)
    except ValueError as err:
        parser.error(str(err))
    return args


def tolerances_of(args: argparse.Namespace) -> Tolerances:
    """The Tolerances that the tolerance options name.

    The Tolerances that the options of add_tolerance_arguments name; ValueError if one is negative or not
    finite.
    """
    tolerances = Tolerances(**{field.name: getattr(args, field.name) for field in dataclasses.fields(Tolerances)})
    tolerances.validate()
    return tolerances
