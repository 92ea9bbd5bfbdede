"""The state-transition graph of a primitive library (paper Figs. 9 and 12) and goal search.

Nodes are the vehicle's steady conditions: ``constrained/rest``, ``constrained/cruise/E0.05``,
``free/rest/R0.43``, ``free/cruise/R0.43/E0.10``, ... Edges are primitives: an accelerate goes from rest
to a cruise, a cruise loops on its node, a decelerate returns to rest, a cruise-to-cruise or lane change
joins two cruise nodes. Building the graph checks every junction (each edge into a node against each edge
out of it) within JUNCTION_TOLERANCE and reports mismatches; pruning removes what cannot be reached from
rest or cannot get back to rest.

Goal search: the quickest path (at the requested time scale) from rest to the goal node; if the request
asks for a longer distance, the path's fastest cruise is repeated until it is covered.
"""
from __future__ import annotations

import dataclasses
import heapq
import math
from collections import defaultdict
from typing import Optional

from swim_planner.catalog import cruise_id, lane_tag
from swim_planner.errors import ManeuverError
from swim_planner.library import PrimitiveLibrary
from swim_planner.maneuver import JUNCTION_TOLERANCE, junction_mismatch
from swim_planner.primitives import PrimitiveSpec, PrimitiveType


def rest_node(constrained: bool, lane_radius_m: float) -> str:
    """The state at rest: one for the constrained vehicle, one per lane (m) for the free one."""
    return "constrained/rest" if constrained else f"free/rest/{lane_tag(lane_radius_m)}"


def cruise_node(constrained: bool, energy_j: float, lane_radius_m: float) -> str:
    """A cruise state is named like the default library's cruise primitive that loops on it."""
    return cruise_id(constrained, energy_j, lane_radius_m)


@dataclasses.dataclass(frozen=True)
class Edge:
    """A primitive as a move from state source to state target, taking duration_s and advancing alpha by advance_rad."""

    primitive_id: str
    source: str
    target: str
    duration_s: float
    advance_rad: float


@dataclasses.dataclass
class StateGraph:
    """The states joined by the library's primitives, with the junctions that did not match and the dead ends pruned."""

    edges: list[Edge]
    mismatches: list[str]                 # junctions that did not match, as readable lines
    pruned: list[str]                     # primitives removed as dead ends

    @property
    def nodes(self) -> set[str]:
        """Every state an edge starts or ends at."""
        return {e.source for e in self.edges} | {e.target for e in self.edges}

    def outgoing(self, node: str) -> list[Edge]:
        """The edges that start at node."""
        return [e for e in self.edges if e.source == node]


def _cruise_node_of(spec: PrimitiveSpec) -> str:
    if spec.energy_j is None:
        raise ManeuverError(f"cruise '{spec.primitive_id}' has no energy level")
    return cruise_node(spec.constrained, spec.energy_j, spec.lane_radius_m)


def _node_of_cruise(library: PrimitiveLibrary, cruise_id: Optional[str], joined_by: PrimitiveSpec) -> str:
    if cruise_id is None:
        raise ManeuverError(f"'{joined_by.primitive_id}' names no cruise it joins")
    return _cruise_node_of(library.spec(cruise_id))


def _endpoints(library: PrimitiveLibrary, spec: PrimitiveSpec) -> tuple[str, str]:
    kind = spec.primitive_type
    if kind is PrimitiveType.CRUISE:
        node = _cruise_node_of(spec)
        return node, node
    if kind is PrimitiveType.ACCELERATE:
        return rest_node(spec.constrained, spec.lane_radius_m), _node_of_cruise(library, spec.end_at, spec)
    if kind is PrimitiveType.DECELERATE:
        return (_node_of_cruise(library, spec.start_from, spec),
                rest_node(spec.constrained, spec.end_lane_radius_m))
    return _node_of_cruise(library, spec.start_from, spec), _node_of_cruise(library, spec.end_at, spec)


def _advance_rad(library: PrimitiveLibrary, primitive_id: str) -> float:
    """The primitive's longitudinal displacement alpha(end) - alpha(start), rad."""
    q = library.get(primitive_id).q
    return float(q[-1, 0] - q[0, 0])


def build_graph(library: PrimitiveLibrary) -> StateGraph:
    """Edges from the library, junctions checked, dead ends pruned."""
    edges = []
    for primitive_id in library.ids():
        spec = library.spec(primitive_id)
        source, target = _endpoints(library, spec)
        edges.append(Edge(primitive_id, source, target, spec.duration_s, _advance_rad(library, primitive_id)))
    mismatches, bad = [], set()
    for into in edges:
        for out in edges:
            if into.target == out.source:
                # a decelerate whose end lag is free (PrimitiveSpec.end_lag_free) rests with the lag states its
                # braking left, which at zero motion put no force on the vehicle; an accelerate starts in still
                # water. The two never follow each other in a plan (concatenate compares the lag states and refuses
                # it): at that rest node the graph joins them on q and qdot
                gap = junction_mismatch(library.get(into.primitive_id), library.get(out.primitive_id),
                                        lag_states=not library.spec(into.primitive_id).end_lag_free)
                if gap > JUNCTION_TOLERANCE:
                    mismatches.append(f"{into.primitive_id} -> {out.primitive_id}: states differ by {gap:.3g}")
                    bad.add(out.primitive_id)
    kept = [e for e in edges if e.primitive_id not in bad]
    alive = _live_nodes(kept)
    pruned = sorted(e.primitive_id for e in kept if e.source not in alive or e.target not in alive) + sorted(bad)
    return StateGraph([e for e in kept if e.source in alive and e.target in alive], mismatches, pruned)


@dataclasses.dataclass(frozen=True)
class PrimitiveSummary:
    """One primitive as an operator chooses it: where it starts and ends in the graph and what it takes."""

    primitive_id: str
    primitive_type: str
    constrained: bool
    start_state: str
    end_state: str
    start_energy_j: float   # energy level E of the start state, J (0 at rest)
    end_energy_j: float     # energy level E of the end state, J (0 at rest)
    duration_s: float       # as stored (time scale 1), s
    advance_rad: float      # alpha(end) - alpha(start), rad
    in_graph: bool          # False: dropped (a junction mismatch or a dead end), still flyable in a sequence


def summarize(library: PrimitiveLibrary, graph: StateGraph) -> list[PrimitiveSummary]:
    """Every primitive of the library, sorted by id, with its graph states and their energy levels."""
    energy_of_state: dict[str, float] = {}
    for primitive_id in library.ids():
        spec = library.spec(primitive_id)
        if spec.primitive_type is PrimitiveType.CRUISE and spec.energy_j is not None:   # a cruise without one: raises
            energy_of_state[_cruise_node_of(spec)] = spec.energy_j                      # in _endpoints, below
    kept = {e.primitive_id for e in graph.edges}
    summaries = []
    for primitive_id in sorted(library.ids()):
        spec = library.spec(primitive_id)
        source, target = _endpoints(library, spec)
        summaries.append(PrimitiveSummary(
            primitive_id, spec.primitive_type.value, spec.constrained, source, target,
            energy_of_state.get(source, 0.0), energy_of_state.get(target, 0.0), spec.duration_s,
            _advance_rad(library, primitive_id), primitive_id in kept))
    return summaries


def _live_nodes(edges: list[Edge]) -> set[str]:
    """Nodes reachable from some rest node that can also get back to a rest node."""
    forward, backward = defaultdict(set), defaultdict(set)
    for e in edges:
        forward[e.source].add(e.target)
        backward[e.target].add(e.source)
    rests = {n for e in edges for n in (e.source, e.target) if "/rest" in n}

    def reach(start: set[str], links) -> set[str]:
        seen, stack = set(start), list(start)
        while stack:
            for nxt in links[stack.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    stack.append(nxt)
        return seen
    return reach(rests, forward) & reach(rests, backward)


def plan_to_goal(  # noqa: C901 - one Dijkstra search, then the cruises repeated to cover the distance asked for
        graph: StateGraph, start: str, goal: str, min_advance_rad: float = 0.0,
        max_duration_s: float = math.inf) -> list[tuple[str, int]]:
    """The quickest primitive sequence from ``start`` to ``goal`` covering at least ``min_advance_rad``.

    Returns [(primitive_id, repeat_index), ...]. Raises ManeuverError if the goal cannot be reached, the
    distance is not finite, or the sequence would last longer than max_duration_s (at lambda = 1).
    """
    if not math.isfinite(min_advance_rad):
        raise ManeuverError(f"the goal distance must be finite, got {min_advance_rad!r} rad")
    nodes = graph.nodes
    for name, node in (("start", start), ("goal", goal)):
        if node not in nodes:
            raise ManeuverError(f"unknown {name} state '{node}'; states: {', '.join(sorted(nodes))}")
    queue: list[tuple[float, int, str, list[Edge]]] = [(0.0, 0, start, [])]
    best: dict[str, float] = {}
    counter = 1
    path = None
    while queue:
        elapsed, _, node, edges = heapq.heappop(queue)
        if node == goal and (edges or min_advance_rad <= 0.0):
            path = edges
            break
        if best.get(node, math.inf) <= elapsed:
            continue
        best[node] = elapsed
        for edge in graph.outgoing(node):
            if edge.source == edge.target and edge.target != goal:
                continue  # a cruise loop only helps to cover distance, added below
            heapq.heappush(queue, (elapsed + edge.duration_s, counter, edge.target, edges + [edge]))
            counter += 1
    if path is None:
        raise ManeuverError(f"no sequence of primitives leads from '{start}' to '{goal}'")
    if not path:
        raise ManeuverError(f"the start is the goal '{goal}': ask for a distance to cover (goal_alpha_rad > 0) or "
                            f"another goal state")
    sequence = [(e.primitive_id, 0) for e in path]
    advance = sum(e.advance_rad for e in path)
    if advance < min_advance_rad:
        cruises = [e for e in graph.edges if e.source == e.target and e.source in {p.target for p in path}]
        if not cruises:
            raise ManeuverError(f"the path to '{goal}' covers {advance:.3f} rad and passes no cruise to repeat")
        fastest = max(cruises, key=lambda e: e.advance_rad / e.duration_s)
        repeats = math.ceil((min_advance_rad - advance) / fastest.advance_rad)
        duration_s = sum(e.duration_s for e in path) + repeats * fastest.duration_s
        if duration_s > max_duration_s:
            raise ManeuverError(f"covering {min_advance_rad:.6g} rad takes {duration_s:.6g} s of swimming, longer "
                                f"than the longest plan served ({max_duration_s:g} s)")
        where = next(i for i, e in enumerate(path) if e.target == fastest.source) + 1
        sequence[where:where] = [(fastest.primitive_id, k) for k in range(repeats)]
    return sequence
