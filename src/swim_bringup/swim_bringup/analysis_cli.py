"""swim-analyze: the paper's measures of a recorded run (Sec. 7), a JSON report, figures, side-by-side tables.

The measures are analysis.py's, of the last plan tracked in the bag: two-norms of the longitudinal, lateral and
Cartesian errors, the final offsets, the duration, peak torques, saturation, the periods at a hard limit (at the
rig's stop: by default the shipped rig file's limits, which sim_node's stops also take; --rig for another rig's)
and the energy used.

Any rosbag2 bag opens (swim-demo's, swim-record's, one recorded by `ros2 bag record`, Humble's included; MCAP or
sqlite3): its topics are listed with their types and message counts, and those whose messages cannot be decoded (a
type neither the bag defines nor this environment knows: rosbag2 records no definition of a type it could not find)
named with why; from joint_states alone, each joint's range and peak speed and the messages' rate; the measures
above when the bag has what they need (tracking_state, and for the constrained vehicle the plan). A topic is found
under its full name (/joint_states: swim-demo's, swim-record's and rosbag2's), a relative one (joint_states, as
other recorders may give it) or one namespace (/test/joint_states). What a bag lacks is named, with why.

Exit status: 0 every bag analysed in full; 1 some bag lacked what the run's measures need (what it holds is
analysed, what it lacks named); 2 some bag could not be read (no bag at the path, a corrupt file) or the output
not written, or the arguments were wrong. Nothing a bag holds ends in a traceback.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from swim_bringup.analysis import BagAnalysis, bag_analysis, bag_section, rig_hard_limits, summary_table
from swim_bringup.bag import BagError
from swim_bringup.figures import write_joint_figure, write_run_figures
from swim_bringup.run_record import RecordedBag, read_bag
from swim_model import RigConfigError

#: swim-analyze's exit status: every bag analysed in full (the run's measures) ...
EXIT_FULL_REPORT = 0
#: ... some bag lacked what the run's measures need: what it holds was analysed, what it lacks named
EXIT_PARTIAL_REPORT = 1
#: ... some bag could not be read (or the output not written, or the arguments were wrong: argparse's status)
EXIT_UNREADABLE = 2


def _label(bag: Path) -> str:
    return bag.parent.name if bag.name == "bag" else str(bag)   # a run folder's bag is named for its folder


def write_outputs(record: RecordedBag, analysis: BagAnalysis, output_dir: Path) -> list[Path]:
    """Write the analysis's files into output_dir; their paths.

    bag_summary.json always; joint_states.png with joint_states; with the run's measures, report.json and the
    run's figures (figures.write_run_figures).
    """
    output_dir.mkdir(parents=True, exist_ok=True)
    paths = [output_dir / "bag_summary.json"]
    paths[0].write_text(json.dumps(analysis.to_json(), indent=2))
    if record.joint_states is not None:
        paths.append(write_joint_figure(record.joint_states.joints, output_dir / "joint_states.png"))
    if analysis.run is not None:
        paths.append(output_dir / "report.json")
        paths[-1].write_text(json.dumps(analysis.run.to_json(), indent=2))
        paths.extend(write_run_figures(record, output_dir))
    return paths


def main(argv: list[str] | None = None) -> int:
    """The swim-analyze command; its exit status."""
    parser = argparse.ArgumentParser(
        prog="swim-analyze", description=__doc__.splitlines()[0],
        epilog=f"exit status: {EXIT_FULL_REPORT} every bag analysed in full; {EXIT_PARTIAL_REPORT} some bag lacked "
               f"what the run's measures need (the rest analysed, what it lacks named); {EXIT_UNREADABLE} some bag "
               f"could not be read, or the output not written")
    parser.add_argument("bags", type=Path, nargs="+",
                        help="rosbag2 bags: folders, or single .mcap or .db3 files (several: a side-by-side table)")
    parser.add_argument("--output", type=Path, default=None,
                        help="folder for bag_summary.json, report.json and figures (one bag)")
    parser.add_argument("--rig", type=Path, default=None,
                        help="the rig file, whose hard stops (its limits) hard_stop_periods counts (default: "
                             "swim_model's shipped rig, every node's when its rig_path is empty)")
    args = parser.parse_args(argv)
    try:
        hard_limits_rad = rig_hard_limits(args.rig)
    except RigConfigError as err:
        print(f"swim-analyze: --rig: {err}", file=sys.stderr)
        return EXIT_UNREADABLE
    status = EXIT_FULL_REPORT
    analyses: dict[str, tuple[RecordedBag, BagAnalysis]] = {}
    for bag in args.bags:
        try:
            record = read_bag(bag)
        except BagError as err:
            print(f"swim-analyze: {err}", file=sys.stderr)
            status = max(status, EXIT_UNREADABLE)
            continue
        analyses[_label(bag)] = (record, analysis := bag_analysis(record, hard_limits_rad))
        print(bag_section(_label(bag), analysis) + "\n")
        if analysis.run is None:
            status = max(status, EXIT_PARTIAL_REPORT)
    runs = {label: analysis.run for label, (_, analysis) in analyses.items() if analysis.run is not None}
    if runs:
        print(summary_table(runs))
    if args.output is not None and len(args.bags) == 1 and analyses:
        try:
            write_outputs(*next(iter(analyses.values())), args.output)
        except (OSError, BagError) as err:
            print(f"swim-analyze: {args.output}: not written: {err}", file=sys.stderr)
            status = EXIT_UNREADABLE
    return status


if __name__ == "__main__":
    sys.exit(main())
