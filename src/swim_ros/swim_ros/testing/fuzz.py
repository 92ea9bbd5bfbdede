"""Hypothesis strategies and settings for the DDS fuzz tests (each node's test/test_fuzz_*.py).

Messages built field by field, valid, borderline and malformed, each example labelled with what the node must do with
it.

Sizes: seeded (derandomize) and sized for CI by default; SWIM_FUZZ_PROFILE=long multiplies every surface's count
by LONG_RUN_FACTOR (the CI total, 675 examples, becomes 10,800; the explicit examples run once in either):

    SWIM_FUZZ_PROFILE=long python -m pytest -q src/swim_sim/test/test_fuzz_sim_node.py
"""
from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import Any, Callable, Optional, Sequence

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

#: how many times the CI count each surface runs with SWIM_FUZZ_PROFILE=long: 16 x 675 is 10,800
LONG_RUN_FACTOR = 16
PROFILE = os.environ.get("SWIM_FUZZ_PROFILE", "ci")
if PROFILE not in ("ci", "long"):
    raise ValueError(f"SWIM_FUZZ_PROFILE must be 'ci' or 'long', got {PROFILE!r}")


def fuzz_settings(ci_examples: int) -> settings:
    """Settings for one surface.

    ci_examples examples (times LONG_RUN_FACTOR in the long run), derandomized so a CI run repeats, no per-example
    deadline (each test asserts its own, over DDS), and the module's node and client shared by every example
    (module-scoped fixtures).
    """
    return settings(max_examples=ci_examples * (LONG_RUN_FACTOR if PROFILE == "long" else 1), derandomize=True,
                    deadline=None, database=None, print_blob=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                           HealthCheck.data_too_large])


# ----- values ------------------------------------------------------------------------------------------------
#: floats no node may take for a physical value
NON_FINITE = (math.nan, math.inf, -math.inf)
#: finite floats at the edges of float64
EDGE_FLOATS = (0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e300, -1e300, 1.7976931348623157e308, -1.7976931348623157e308)


def any_float() -> st.SearchStrategy[float]:
    """Every kind of float64: non-finite, edges, and anything else."""
    return st.one_of(st.sampled_from(NON_FINITE + EDGE_FLOATS), st.floats(allow_nan=True, allow_infinity=True))


def unicode_name() -> st.SearchStrategy[str]:
    r"""A name no node knows.

    Random unicode, empty included; no surrogates (rosidl strings are UTF-8) and no NUL (a C string ends there, so
    "alpha\0" would arrive as a known name).
    """
    return st.text(st.characters(exclude_categories=["Cs"], exclude_characters="\x00"), max_size=12)


# ----- joint states ------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class JointStateFields:
    """A sensor_msgs/JointState's name, position, velocity and effort, and why it is malformed.

    The reason is None when it is not; a well-formed message may still be out of a node's bounds, which the test
    decides.
    """

    name: list[str]
    position: list[float]
    velocity: list[float]
    effort: list[float]
    defect: Optional[str]


@st.composite
def joint_states(  # noqa: C901 - one branch per kind of malformed field the strategy draws
        draw: Any, joints: tuple[str, ...], value: st.SearchStrategy[float],
        velocity_value: Optional[st.SearchStrategy[float]] = None, with_velocity: bool = True,
        field: str = "position") -> JointStateFields:
    """A JointState for joints.

    Well formed (the joints once each, any order, one finite value each in `field`, velocities empty or one each) with
    values from value, or malformed in one way (unknown, missing or repeated names, random unicode, a length that does
    not match, a non-finite value).
    """
    velocity_value = value if velocity_value is None else velocity_value
    names = list(draw(st.permutations(joints)))
    values = [draw(value) for _ in names]
    velocities = [draw(velocity_value) for _ in names] if with_velocity and draw(st.booleans()) else []
    defects = (None, None, None, "unknown name", "missing name", "repeated name", "unicode names", "short values",
               "long values", "non-finite value", "empty")
    defect = draw(st.sampled_from(defects + (("short velocities", "non-finite velocity") if with_velocity else ())))
    if defect == "unknown name":
        unknown = [n for n in ("R", "Phi", "theta ", "psi", "") if n not in joints]
        names[draw(st.integers(0, len(names) - 1))] = draw(st.sampled_from(unknown))
    elif defect == "missing name":
        index = draw(st.integers(0, len(names) - 1))
        del names[index], values[index]
        velocities = velocities[:len(names)]
    elif defect == "repeated name":
        names[0] = names[-1]
    elif defect == "unicode names":
        names = draw(st.lists(unicode_name(), min_size=len(names), max_size=len(names)))
        if sorted(names) == sorted(joints):
            defect = None
    elif defect == "short values":
        values = values[:draw(st.integers(0, len(values) - 1))]
    elif defect == "long values":
        values = values + [draw(value) for _ in range(draw(st.integers(1, 3)))]
    elif defect == "non-finite value":
        values[draw(st.integers(0, len(values) - 1))] = draw(st.sampled_from(NON_FINITE))
    elif defect == "short velocities":
        velocities = [draw(velocity_value) for _ in range(draw(st.integers(1, len(names) - 1)))]
    elif defect == "non-finite velocity":
        if velocities:
            velocities[draw(st.integers(0, len(velocities) - 1))] = draw(st.sampled_from(NON_FINITE))
        else:
            defect = None
    elif defect == "empty":
        names, values, velocities = [], [], []
    if defect is None and not all(math.isfinite(v) for v in values + velocities):
        defect = "non-finite value"   # a value strategy that can draw NaN or inf made this one malformed
    positions, efforts = (values, []) if field == "position" else ([], values)
    return JointStateFields(names, positions, velocities, efforts, defect)


def to_joint_state(fields: JointStateFields, stamp: Any = None) -> Any:
    """The sensor_msgs/JointState of fields, stamped with stamp if given."""
    from sensor_msgs.msg import JointState
    message = JointState(name=fields.name, position=fields.position, velocity=fields.velocity, effort=fields.effort)
    if stamp is not None:
        message.header.stamp = stamp
    return message


def in_order(fields: JointStateFields, joints: tuple[str, ...], values: list[float]) -> list[float]:
    """A well-formed message's values in the order of joints."""
    return [values[fields.name.index(joint)] for joint in joints]


def torques() -> st.SearchStrategy[float]:
    """Joint torques, N m: within the motor limits (about 1.25 and 0.52 N m), past them, and at float64's edges."""
    return st.one_of(st.floats(-1.5, 1.5), st.sampled_from((-50.0, 50.0, 1e300, -1e300, 0.0, -0.0)))


# ----- parameters --------------------------------------------------------------------------------------------
def parameter_values() -> st.SearchStrategy[Any]:
    """Any value a parameter may be set to: every type rclpy carries, with malformed numbers."""
    return st.one_of(st.booleans(), st.integers(-2 ** 63, 2 ** 63 - 1), any_float(), unicode_name(),
                     st.lists(any_float(), max_size=5), st.lists(st.integers(-10, 10), min_size=1, max_size=5),
                     st.lists(unicode_name(), min_size=1, max_size=3))


def parameter_sets(names: list[str]) -> st.SearchStrategy[tuple[str, Any]]:
    """(name, value): a declared name or an unknown one, with a value of any type."""
    return st.tuples(st.one_of(st.sampled_from(names), unicode_name().map(lambda n: f"fuzz.{n}")),
                     parameter_values())


def is_non_finite_number(value: Any) -> bool:
    """A float (or list of floats) with a NaN or infinite entry: no physical parameter may take it."""
    values = value if isinstance(value, list) else [value]
    return any(isinstance(v, float) and not math.isfinite(v) for v in values)


def set_and_check_parameter(parameters: Any, name: str, value: Any, read_only: Any, deadline_s: float,
                            counts: dict[str, int]) -> None:
    """Set one fuzzed value on a node (swim_ros.calls.ParameterCalls) and check the reply.

    Answered within deadline_s; a read-only or unknown ("fuzz." prefixed) name or a non-finite number refused; an
    accepted value read back; a refusal with a reason. counts["accepted"] or counts["refused"] goes up by one. A value
    rclpy itself cannot carry (a list of mixed types) never reaches the node and is skipped.
    """
    from rclpy.parameter import Parameter
    try:
        parameter = Parameter(name, value=value)
    except TypeError:
        return
    start = time.monotonic()
    reply = parameters.set([parameter])[0]
    assert time.monotonic() - start < deadline_s
    counts["accepted" if reply.successful else "refused"] += 1
    if name in read_only or name.startswith("fuzz.") or is_non_finite_number(value):
        assert not reply.successful, (name, value)
    if reply.successful:
        assert list(np.atleast_1d(parameters.get([name])[0])) == list(np.atleast_1d(value))
    else:
        assert reply.reason


def fuzz_parameter_sets(parameters: Any, specs: Sequence[Any], ci_examples: int, deadline_s: float,
                        alive: Callable[[], bool], launched: Optional[dict[str, Any]] = None) -> dict[str, int]:
    """Fuzz one node's parameters with ci_examples sets, then set every changeable one back.

    The sets are parameter_sets over the names of specs (a node's swim_ros.parameters.ParameterSpec table), made through
    parameters (swim_ros.calls.ParameterCalls), each checked by set_and_check_parameter and the node alive() after it;
    then every changeable parameter is set back to its launch value (launched: name -> value, else its default), which
    must be accepted. Returns the counts of accepted and refused sets; a run with no refusal fails (the unknown and
    non-finite ones must be refused).
    """
    from rclpy.parameter import Parameter
    launched = launched or {}
    read_only = {spec.name for spec in specs if spec.read_only}
    counts = {"accepted": 0, "refused": 0}
    parameters.get([specs[0].name]), parameters.set([])   # discovery of the parameter services, outside deadlines

    @fuzz_settings(ci_examples)
    @given(change=parameter_sets([spec.name for spec in specs]))
    def set_one(change: tuple[str, Any]) -> None:
        set_and_check_parameter(parameters, *change, read_only, deadline_s, counts)
        assert alive()

    try:
        set_one()
    finally:
        restored = [Parameter(spec.name, value=launched.get(spec.name, spec.default))
                    for spec in specs if not spec.read_only]
        assert all(result.successful for result in parameters.set(restored))
    assert counts["refused"] > 0
    return counts
