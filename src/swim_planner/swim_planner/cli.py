"""swim-primitives: build, list, show and plot primitive libraries.

    swim-primitives build [LIBRARY] [--flow ideal|circulatory] [--set constrained|free|all] [--only ID ...]
                          [--workers N] [--scheduler ADDR] [--lqr-weights FILE.yaml]
    swim-primitives list  [LIBRARY] [--flow ideal|circulatory]
    swim-primitives show  ID [--library LIBRARY] [--flow ideal|circulatory]
    swim-primitives plot  ID [--library LIBRARY] [--flow ideal|circulatory] [--output FILE.png]
    swim-primitives compare ID [--library LIBRARY] [--segments 1|2] [--evaluations N]
    swim-primitives flows ID [--ideal-library LIBRARY] [--circulatory-library LIBRARY] [--output FILE.png] [--json]

`compare` solves a constrained cruise or accelerate again by the paper's own method (Fourier series, or
eq. 11's polynomial sinusoids in one or two segments, by Nelder-Mead as MATLAB's fmin) and prints both
methods' index J, how far each misses its constraints, and the wall time, as JSON.

`flows` draws a primitive of the ideal library and the same id of the circulatory one on the same axes (speed
along the lane, heave, pitch, angle of attack, thrust, the motors' power; a cruise: one solved cycle each;
swim_planner.plots.plot_flows) and prints their summary numbers, as JSON with --json (then the figure only
with --output).

--flow is swim_model's flow model: "ideal" (the paper's, the default) or "circulatory". A build solves that
model's primitive set (catalog.default_specs or catalog.circulatory_specs) and refuses to add to a library of the
other model. LIBRARY defaults to the library shipped with swim_planner for that flow model; list, show and plot
of a LIBRARY named read it whatever its flow model. Builds are resumable: primitives already in
the library are kept. Jobs run in local processes, or on a Dask cluster when --scheduler names one. Each
primitive is stored with its tracking gains (the Riccati solution P(t) and G'P, swim_control.riccati);
when the LQ weights change, a build recomputes only the gains.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import json
import sys
from pathlib import Path

from swim_model import SwimModelError, load_rig
from swim_model.flow import FLOW_MODELS
from swim_planner import catalog
from swim_planner.build import build_library, dependencies, local_executor
from swim_planner.errors import PlannerError
from swim_planner.gains import load_lqr_weights
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="swim-primitives", description=__doc__.splitlines()[0])
    parser.add_argument("--rig", type=Path, default=None, help="rig parameter file (default: the shipped one)")
    commands = parser.add_subparsers(dest="command", required=True)
    flow = argparse.ArgumentParser(add_help=False)
    flow.add_argument("--flow", choices=FLOW_MODELS, default="ideal",
                      help="flow model of the primitives (default: ideal, the paper's)")
    build = commands.add_parser("build", help="solve the primitives not yet in a library", parents=[flow])
    build.add_argument("library", type=Path, nargs="?", default=None)
    build.add_argument("--set", choices=("constrained", "free", "all"), default="all")
    build.add_argument("--only", nargs="+", default=None, help="these ids (and what they join) only")
    build.add_argument("--workers", type=int, default=2, help="local worker processes")
    build.add_argument("--scheduler", default=None, help="Dask scheduler address (tcp://host:port)")
    build.add_argument("--lqr-weights", type=Path, default=None,
                       help="YAML of swim_control LqrWeights fields for the stored tracking gains "
                            "(default: the flow's, catalog.lqr_weights); changed weights recompute the gains only")
    listing = commands.add_parser("list", help="one line per primitive", parents=[flow])
    listing.add_argument("library", type=Path, nargs="?", default=None)
    for name in ("show", "plot"):
        sub = commands.add_parser(name, help=f"{name} one primitive", parents=[flow])
        sub.add_argument("primitive_id")
        sub.add_argument("--library", type=Path, default=None)
        if name == "plot":
            sub.add_argument("--output", type=Path, default=None, help="PNG file (default: <id>.png)")
    compare = commands.add_parser("compare", help="solve one primitive by the paper's method beside ours")
    compare.add_argument("primitive_id")
    compare.add_argument("--library", type=Path, default=None)
    compare.add_argument("--segments", type=int, choices=(1, 2), default=2,
                         help="accelerate: eq. 11 in one 18-coefficient piece or the paper's two of 9")
    compare.add_argument("--evaluations", type=int, default=6000, help="Nelder-Mead evaluations per solve")
    flows = commands.add_parser("flows", help="one primitive of the ideal and of the circulatory flow side by side")
    flows.add_argument("primitive_id")
    flows.add_argument("--ideal-library", type=Path, default=None, help="default: the shipped ideal library")
    flows.add_argument("--circulatory-library", type=Path, default=None,
                       help="default: the shipped circulatory library")
    flows.add_argument("--output", type=Path, default=None, help="PNG file (default: <id>_flows.png)")
    flows.add_argument("--json", action="store_true",
                       help="print the summary numbers as JSON (and draw the figure only with --output)")
    return parser


def _select(specs, only):
    if not only:
        return specs
    by_id = {s.primitive_id: s for s in specs}
    unknown = [i for i in only if i not in by_id]
    if unknown:
        raise PlannerError(f"unknown primitive ids: {', '.join(unknown)}")
    wanted, stack = set(), list(only)
    while stack:
        spec = by_id[stack.pop()]
        if spec.primitive_id not in wanted:
            wanted.add(spec.primitive_id)
            stack += dependencies(spec)
    return [s for s in specs if s.primitive_id in wanted]


def _executor(args) -> concurrent.futures.Executor:
    if args.scheduler:
        from distributed import Client
        return Client(args.scheduler).get_executor()
    return local_executor(args.workers)


def _load(args, rig) -> PrimitiveLibrary:
    """The library named (of whichever flow model), or the shipped one of --flow."""
    if args.library is not None:
        return PrimitiveLibrary.load(args.library, rig, flow_model=None)
    return PrimitiveLibrary.load(default_library_path(args.flow), rig, args.flow)


def command_build(args, rig) -> int:
    """``swim-primitives build``: solve the selected specs missing from the library; the exit code."""
    from tqdm import tqdm
    specs_of_flow = catalog.circulatory_specs if args.flow == "circulatory" else catalog.default_specs
    every = specs_of_flow(rig)
    wanted = {"constrained": (True,), "free": (False,), "all": (True, False)}[args.set]
    specs = _select([s for s in every if s.constrained in wanted], args.only)
    flow_weights = catalog.lqr_weights(args.flow)
    weights = load_lqr_weights(args.lqr_weights, flow_weights) if args.lqr_weights else flow_weights
    library = PrimitiveLibrary.create_or_open(args.library or default_library_path(args.flow), rig,
                                              lqr_weights=weights, flow_model=args.flow)
    with tqdm(total=len(specs), unit="primitive", file=sys.stderr) as bar, _executor(args) as executor:
        def progress(primitive_id: str, status: str) -> None:
            bar.update(1)
            bar.write(f"{primitive_id}: {status}")
        failed = build_library(library, specs, executor, progress=progress,
                               workers=None if args.scheduler else args.workers)
    print(f"{library.path}: {len(library)} primitives, {library.flow_model} flow"
          + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


def command_list(args, rig) -> int:
    """``swim-primitives list``: one line per primitive of the library; the exit code."""
    library = _load(args, rig)
    print(f"{'id':48s} {'type':16s} {'T (s)':>6s} {'J':>9s} {'solve (s)':>9s}  status")
    for primitive_id in library.ids():
        e = library.entry(primitive_id)
        print(f"{primitive_id:48s} {e['spec']['primitive_type']:16s} {e['spec']['duration_s']:6.2f} "
              f"{e['index_j']:9.4f} {e['solve_time_s']:9.2f}  {e['solver_status']}")
    return 0


def command_show(args, rig) -> int:
    """``swim-primitives show``: a primitive's manifest entry with its end states and peak torques, as JSON."""
    library = _load(args, rig)
    entry = dict(library.entry(args.primitive_id))
    primitive = library.get(args.primitive_id)
    entry["start_q"], entry["end_q"] = primitive.q[0].tolist(), primitive.q[-1].tolist()
    entry["peak_torque_n_m"] = abs(primitive.torque).max(axis=0).tolist()
    print(json.dumps(entry, indent=2))
    return 0


def command_plot(args, rig) -> int:
    """``swim-primitives plot``: a primitive's figure written to a PNG file."""
    from swim_planner.plots import plot_primitive
    library = _load(args, rig)
    output = args.output or Path(args.primitive_id.replace("/", "_") + ".png")
    plot_primitive(library.get(args.primitive_id), output)
    print(f"wrote {output}")
    return 0


def command_compare(args, rig) -> int:
    """``swim-primitives compare``: a constrained cruise or accelerate against the paper's method's, as JSON."""
    from swim_model import VehicleModel
    from swim_planner import paper_method
    from swim_planner.primitives import PrimitiveType
    library = PrimitiveLibrary.load(args.library or default_library_path(), rig)
    ours = library.get(args.primitive_id)
    spec = ours.spec
    if not spec.constrained or spec.primitive_type not in (PrimitiveType.CRUISE, PrimitiveType.ACCELERATE):
        raise PlannerError(f"{args.primitive_id}: the paper's method is implemented for constrained cruises and "
                           "accelerates only")
    model = VehicleModel(rig, constrained=True, lane_radius_m=spec.lane_radius_m)
    report = {"primitive": args.primitive_id, "collocation": {
        "index_j": ours.index_j / spec.cycles, "solve_time_s": library.entry(args.primitive_id)["solve_time_s"]}}
    if spec.primitive_type is PrimitiveType.CRUISE:
        cruise = paper_method.solve_fourier_cruise(model, spec, max_evaluations=args.evaluations)
        report["paper_method"] = {"parameterization": "Fourier series, 2 harmonics", "index_j": cruise.index_j,
                                  "energy_error_j": cruise.energy_error_j, "wall_s": cruise.wall_s}
        report["index_j_per"] = "cycle"
    else:
        assert spec.end_at is not None   # an accelerate ends at its cruise
        end_state = library.get(spec.end_at).start_state
        accelerate = paper_method.solve_polynomial_sine_accelerate(model, spec, end_state, segments=args.segments,
                                                                   max_evaluations=args.evaluations)
        report["paper_method"] = {"parameterization": f"eq. 11 in {args.segments} segment(s)",
                                  "index_j": accelerate.index_j, "boundary_error": accelerate.boundary_error,
                                  "wall_s": accelerate.wall_s}
        report["index_j_per"] = "primitive"
    print(json.dumps(report, indent=2))
    return 0


def command_flows(args, rig) -> int:
    """``swim-primitives flows``: a primitive of the ideal and of the circulatory library side by side."""
    from swim_model import VehicleModel
    from swim_planner.plots import flow_summary, flow_traces, plot_flows
    sides, summaries = [], {}
    for flow, path in (("ideal", args.ideal_library), ("circulatory", args.circulatory_library)):
        library = PrimitiveLibrary.load(path or default_library_path(flow), rig, flow)
        if args.primitive_id not in library:
            raise PlannerError(f"'{args.primitive_id}' is not in the {flow} library at {library.path}; flows needs "
                               f"an id of both libraries (`swim-primitives list --flow {flow}` lists its ids)")
        primitive = library.get(args.primitive_id)
        spec = primitive.spec
        traces = flow_traces(primitive, VehicleModel(rig, constrained=spec.constrained,
                                                     lane_radius_m=spec.lane_radius_m, flow=flow))
        sides.append(traces)
        summaries[flow] = flow_summary(primitive, traces)
    report = {"primitive": args.primitive_id,
              "thrust": "time average of the fluid's force on the foil (added mass, plus the circulatory flow's "
                        "force in the circulatory model) along the hub's tangent at the foil frame origin F",
              **summaries}
    output = args.output or Path(args.primitive_id.replace("/", "_") + "_flows.png")
    if args.output is not None or not args.json:
        plot_flows(sides, args.primitive_id, output)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"wrote {output}")
    for flow, numbers in summaries.items():
        suction = ("" if numbers["leading_edge_suction_parameter_p95"] is None else
                   f", A0 p95 {numbers['leading_edge_suction_parameter_p95']:.3f} (past critical "
                   f"{100.0 * numbers['time_past_critical_suction']:.0f} % of the time)")
        print(f"{flow:12s} speed {numbers['mean_speed_m_s']:.3f} m/s, AoA p95 {numbers['angle_of_attack_p95_deg']:.1f} "
              f"deg, power {numbers['mean_power_w']:.4f} W, thrust {numbers['mean_thrust_n']:.4f} N{suction}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """The ``swim-primitives`` command line; its exit code."""
    args = _parser().parse_args(argv)
    commands = {"build": command_build, "list": command_list, "show": command_show, "plot": command_plot,
                "compare": command_compare, "flows": command_flows}
    try:
        rig = load_rig(args.rig)
        return commands[args.command](args, rig)
    except (PlannerError, SwimModelError) as err:
        print(f"swim-primitives: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
