"""planner_node: serves maneuver requests (request_maneuver, list_primitives) from the primitive library.

Services, the plan topic, repeated requests and the parameters (flow model, LQ retuning, plan bounds): see
src/swim_planner/README.md, section "planner_node". Concatenation and time scaling: docs/model_and_method.md,
section "4. Maneuvers: library, graph, concatenation and time scaling".
"""
from __future__ import annotations

import collections
import dataclasses
import functools
import threading

from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from swim_interfaces.msg import PlannedTrajectory, PrimitiveInfo
from swim_interfaces.srv import ListPrimitives, RequestManeuver

from swim_control.trajectory import Trajectory
from swim_model import SwimModelError, load_rig
from swim_model.flow import FLOW_MODELS
from swim_planner.errors import PlannerError
from swim_planner.gains import RetunedLibrary, load_lqr_weights
from swim_planner.graph import build_graph, plan_to_goal, rest_node, summarize
from swim_planner.library import PrimitiveLibrary
from swim_planner.maneuver import (
    DEFAULT_BOUNDS,
    PlanBounds,
    check_plan_size,
    check_start_alpha,
    concatenate,
    expand_sequence,
)
from swim_planner.paths import default_library_path
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec, one_of, positive
from swim_ros.qos import LATCHED_QOS
from swim_ros.trajectory_messages import trajectory_to_message
from swim_ros.transport import use_large_message_transport

#: threads serving requests at once: a request whose primitives need new gains does not hold up the others
SERVICE_THREADS = 4
#: replies kept by request id for repeated requests; assumed: a client repeats within seconds, and 64 replies
#: cover every client of a rig many times over
ANSWERS_KEPT = 64
#: ceilings of the plan bounds a user may set: ten times the defaults (maneuver.PlanBounds), about 4 GB of plan at
#: the sample ceiling; past them a value is a typo, not a longer maneuver
MAX_PLAN_DURATION_CEILING_S = 10 * DEFAULT_BOUNDS.max_duration_s
MAX_PLAN_SAMPLES_CEILING = 10 * DEFAULT_BOUNDS.max_samples


def _weights_file_loads(path: str) -> str | None:
    """A check: an LQ weights file that does not load is refused with the loader's reason."""
    if not path:
        return None
    try:
        load_lqr_weights(path)
    except PlannerError as err:
        return f"does not load: {err}"
    return None


#: the planner's parameters (swim_ros.parameters); the library and rig are read once, at start
PARAMETERS = (
    ParameterSpec("flow_model", "ideal", "flow model of the plans: ideal (the paper's) or circulatory",
                  read_only=True, check=one_of(*FLOW_MODELS)),
    ParameterSpec("library_path", "", "primitive library folder, built with flow_model (empty: the one shipped "
                  "for flow_model)", read_only=True),
    ParameterSpec("rig_path", "", "rig YAML file (empty: the shipped rig)", read_only=True),
    ParameterSpec("default_time_scale", 1.0, "lambda for requests whose time_scale is 0 (Theorem 1)",
                  range=(0.1, 10.0)),
    ParameterSpec("lqr_weights_path", "", "YAML of swim_control LqrWeights fields (empty: the gains stored "
                  "in the library); applies to the plans made after it is set", check=_weights_file_loads),
    ParameterSpec("max_plan_duration_s", DEFAULT_BOUNDS.max_duration_s, "longest plan served, s",
                  range=(0.0, MAX_PLAN_DURATION_CEILING_S), check=positive),
    ParameterSpec("max_plan_samples", DEFAULT_BOUNDS.max_samples, "most samples in a plan served",
                  range=(1, MAX_PLAN_SAMPLES_CEILING)),
)


@dataclasses.dataclass(frozen=True)
class PlannerSettings:
    """PARAMETERS' values (swim_ros.parameters.NodeSettings); the plan bounds checked together (ValueError)."""

    flow_model: str
    library_path: str
    rig_path: str
    default_time_scale: float
    lqr_weights_path: str
    max_plan_duration_s: float
    max_plan_samples: int

    def __post_init__(self) -> None:
        """Check the plan bounds (ValueError unless each is positive and finite)."""
        self.bounds.validate()

    @property
    def bounds(self) -> PlanBounds:
        """The bounds of the plans served."""
        return PlanBounds(max_duration_s=self.max_plan_duration_s, max_samples=self.max_plan_samples,
                          max_abs_start_alpha_rad=DEFAULT_BOUNDS.max_abs_start_alpha_rad)


class AnswerMemory:
    """Replies by request id, the latest ANSWERS_KEPT.

    A repeat that arrives while the first is still being planned waits for that reply instead of planning again.
    """

    def __init__(self, size: int = ANSWERS_KEPT) -> None:
        self.size = size
        self._lock = threading.Lock()
        self._answers: collections.OrderedDict[str, tuple[threading.Event, list]] = collections.OrderedDict()

    def claim(self, request_id: str) -> tuple[bool, threading.Event, list]:
        """(first, done, box): first is True for the first request with this id, which must answer() it."""
        with self._lock:
            if request_id in self._answers:
                done, box = self._answers[request_id]
                return False, done, box
            done, box = threading.Event(), []
            self._answers[request_id] = (done, box)
            while len(self._answers) > self.size:
                self._answers.popitem(last=False)
            return True, done, box

    @staticmethod
    def answer(done: threading.Event, box: list, response) -> None:
        """Store the reply for request id's waiters and wake them."""
        box.append(response)
        done.set()


class PlannerNode(Node):
    """The planner as a node: lists the library's primitives and plans maneuvers on request."""

    def __init__(self) -> None:
        super().__init__("planner_node")
        self.parameters = NodeSettings(self, PARAMETERS, PlannerSettings, on_change=self._apply_parameters)
        settings = self.parameters.current
        flow_model = settings.flow_model
        self.rig = load_rig(settings.rig_path or None)
        self.library = PrimitiveLibrary.load(settings.library_path or default_library_path(flow_model), self.rig,
                                             flow_model)
        self.graph = build_graph(self.library)
        self._plan_library = self._retuned(settings.lqr_weights_path)
        self.answers = AnswerMemory()
        for line in self.graph.mismatches:
            self.get_logger().warning(f"junction mismatch, primitive dropped from the graph: {line}")
        self.plan_publisher = self.create_publisher(PlannedTrajectory, "plan", LATCHED_QOS)
        self.create_service(RequestManeuver, "request_maneuver", self.on_request,
                            callback_group=ReentrantCallbackGroup())
        summaries = summarize(self.library, self.graph)
        self._primitive_list = ListPrimitives.Response(
            flow_model=flow_model, library_digest=self.library.digest(), states=sorted(self.graph.nodes),
            primitives=[PrimitiveInfo(**dataclasses.asdict(summary)) for summary in summaries])
        self.create_service(ListPrimitives, "list_primitives", self.on_list, callback_group=ReentrantCallbackGroup())
        self.get_logger().info(f"serving {len(self.library)} primitives of the {flow_model} flow model from "
                               f"{self.library.path}")

    def _retuned(self, lqr_weights_path: str) -> PrimitiveLibrary | RetunedLibrary:
        """The library plans are made from: its stored gains, or gains for the weights in lqr_weights_path."""
        if not lqr_weights_path:
            return self.library
        return RetunedLibrary(self.library, load_lqr_weights(lqr_weights_path, self.library.lqr_weights))

    @property
    def bounds(self) -> PlanBounds:
        """The bounds of the plans served, from the current parameters."""
        return self.parameters.current.bounds

    def _apply_parameters(self, previous: PlannerSettings, current: PlannerSettings) -> None:
        """Post-set callback: accepted values take effect.

        New bounds (read from the settings by each request) and LQ weights serve the requests that come after.
        """
        if current.lqr_weights_path != previous.lqr_weights_path:
            try:
                self._plan_library = self._retuned(current.lqr_weights_path)
            except PlannerError as err:   # the file changed between the check and now: keep the weights in use
                self.get_logger().error(f"LQ weights not applied, those in use kept: {err}")
                return
            self.get_logger().info(f"LQ weights for new plans: {current.lqr_weights_path or 'those stored'}")

    def on_list(self, request: ListPrimitives.Request, response: ListPrimitives.Response) -> ListPrimitives.Response:
        """The list_primitives service: the library's primitives."""
        return self._primitive_list

    def on_request(self, request: RequestManeuver.Request,
                   response: RequestManeuver.Response) -> RequestManeuver.Response:
        """The request_maneuver service: a plan, or the reply already given to the same request id."""
        if not request.request_id:
            return self._answer(request, response)
        first, done, box = self.answers.claim(request.request_id)
        if not first:
            done.wait()
            self.get_logger().info(f"request {request.request_id} repeated: its reply sent again")
            return box[0]
        try:
            response = self._answer(request, response)
        finally:
            self.answers.answer(done, box, response)
        return response

    def _answer(self, request: RequestManeuver.Request,
                response: RequestManeuver.Response) -> RequestManeuver.Response:
        try:
            plan = self.plan(request)
        except PlannerError as err:
            response.success, response.message = False, str(err)
            self.get_logger().warning(f"maneuver refused: {err}")
            return response
        response.success = True
        response.message = f"planned {len(plan.segments)} segments, {plan.duration_s:.3f} s"
        response.plan = trajectory_to_message(plan, self.get_clock().now().to_msg())
        self.plan_publisher.publish(response.plan)
        return response

    def plan(self, request: RequestManeuver.Request) -> Trajectory:
        """The plan a request asks for: its sequence of primitives, or the way to its goal state, concatenated."""
        settings = self.parameters.current
        time_scale = request.time_scale or settings.default_time_scale
        bounds, library = settings.bounds, self._plan_library
        check_start_alpha(request.start_alpha_rad, bounds)
        if request.mode == RequestManeuver.Request.MODE_SEQUENCE:
            check_plan_size(library, list(request.primitive_ids), list(request.repeat_counts), time_scale, bounds)
            sequence = expand_sequence(list(request.primitive_ids), list(request.repeat_counts))
        elif request.mode == RequestManeuver.Request.MODE_GOAL:
            start = request.start_state or rest_node(request.goal_state.startswith("constrained"),
                                                     self.rig.lane_1_radius_m)
            check_plan_size(library, [], [], time_scale, bounds)      # the time scale, before it divides
            sequence = plan_to_goal(self.graph, start, request.goal_state, request.goal_alpha_rad,
                                    bounds.max_duration_s * time_scale)
            check_plan_size(library, [pid for pid, _ in sequence], [], time_scale, bounds)
        else:
            modes = RequestManeuver.Request
            raise PlannerError(f"unknown mode {request.mode}: use MODE_SEQUENCE ({modes.MODE_SEQUENCE}) "
                               f"or MODE_GOAL ({modes.MODE_GOAL})")
        # the libraries are thread-safe; requests run concurrently (reentrant group), so one whose new gains are
        # being computed does not hold up the others
        return concatenate(library, self.rig, sequence, time_scale, request.start_alpha_rad)


def main(args: list[str] | None = None) -> None:
    """Run the planner node in its own process (ros2 run swim_planner planner_node)."""
    run_node(PlannerNode, args, name="planner_node", fatal_errors=(PlannerError, SwimModelError),
             executor=functools.partial(MultiThreadedExecutor, num_threads=SERVICE_THREADS),
             transport=use_large_message_transport)


if __name__ == "__main__":
    main()
