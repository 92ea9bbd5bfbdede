"""VehicleModel.integrate_rk4 runs the compiled RK4 step in chunks of RK4_CHUNK_STEPS steps called on buffers: the
trajectory must be the step's, applied once per torque row, bit for bit, whatever the number of steps and however
many threads integrate on one model at once.

The reference is the compiled ``rk4_step`` called through CasADi (``VehicleModel.numeric``), one step at a time with
the previous result as its start: a different call path to the same generated C, so any slip in the chunking (a
torque row off by one, a chunk started from the wrong state, a buffer overwritten by another call) shows as a
difference.
"""
import threading

import numpy as np
import pytest

from swim_model import StateError, VehicleModel
from swim_model.vehicle import RK4_CHUNK_STEPS

MODELS = {(flow, constrained): VehicleModel(constrained=constrained, flow=flow)
          for flow in ("ideal", "circulatory") for constrained in (False, True)}
STEP_S = 0.001
# step counts below, at and across the chunk sizes: one, a sum of several chunks, one past the largest chunk, and
# more than two of the largest
STEP_COUNTS = (1, 7, RK4_CHUNK_STEPS[-1] + 1, 2 * RK4_CHUNK_STEPS[-1] + RK4_CHUNK_STEPS[-2] + 3)


def swimming_start(model: VehicleModel, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """(q, qdot[, lag]): the vehicle and its foil moving, the flow's lag states (if any) away from rest."""
    q = rng.uniform(-0.5, 0.5, model.nq)
    if not model.constrained:
        q[1] = rng.uniform(0.4, 0.5)
    qdot = rng.uniform(-1.0, 1.0, model.nq)
    return (q, qdot) + ((rng.uniform(-0.1, 0.1, model.n_lag),) if model.n_lag else ())


def step_by_step(model: VehicleModel, start: tuple[np.ndarray, ...], torques: np.ndarray) -> np.ndarray:
    """(n + 1, nx): the compiled RK4 step through CasADi, once per torque row."""
    step = model.numeric["rk4_step"]
    states = [np.concatenate(start)]
    for torque in torques:
        states.append(np.asarray(step(states[-1], torque, STEP_S), dtype=float).ravel())
    return np.array(states)


def integrate(model: VehicleModel, start: tuple[np.ndarray, ...], torques: np.ndarray) -> np.ndarray:
    q, qdot, *lag = start
    return np.column_stack(model.integrate_rk4(q, qdot, torques, STEP_S, lag=lag[0] if lag else None))


@pytest.mark.parametrize("flow, constrained", sorted(MODELS))
def test_chunks_are_the_step_applied_once_per_torque_bit_for_bit(flow, constrained):
    model = MODELS[flow, constrained]
    rng = np.random.default_rng(3)
    for steps in STEP_COUNTS:
        start = swimming_start(model, rng)
        torques = rng.uniform(-0.3, 0.3, (steps, 2))   # a different torque every step
        trajectory = integrate(model, start, torques)
        assert trajectory.shape == (steps + 1, model.nx)
        np.testing.assert_array_equal(trajectory, step_by_step(model, start, torques))
        assert np.abs(trajectory[-1] - trajectory[0]).max() > 1e-3   # it moved


def test_no_steps_gives_the_start_alone():
    model = MODELS["circulatory", False]
    start = swimming_start(model, np.random.default_rng(4))
    q, qdot, lag = model.integrate_rk4(*start[:2], np.zeros((0, 2)), STEP_S, lag=start[2])
    np.testing.assert_array_equal(np.concatenate([q[0], qdot[0], lag[0]]), np.concatenate(start))
    assert q.shape == (1, model.nq) and lag.shape == (1, model.n_lag)


def test_threads_on_one_model_get_their_own_trajectories():
    """The chunks' buffers are shared by the model's calls: four threads integrating different runs at once get what
    each run gives alone."""
    model = MODELS["circulatory", False]
    rng = np.random.default_rng(6)
    runs = [(swimming_start(model, rng), rng.uniform(-0.3, 0.3, (300, 2))) for _ in range(4)]
    alone = [integrate(model, start, torques) for start, torques in runs]
    together: list[list[np.ndarray]] = [[] for _ in runs]

    def work(index: int) -> None:
        for _ in range(10):
            together[index].append(integrate(model, *runs[index]))

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(runs))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for expected, results in zip(alone, together):
        assert len(results) == 10
        for result in results:
            np.testing.assert_array_equal(result, expected)


def test_bad_torques_are_refused():
    model = MODELS["circulatory", False]
    q, qdot, lag = swimming_start(model, np.random.default_rng(8))
    for torques in (np.zeros((3, 3)), np.zeros(2), np.array([[0.0, np.inf]])):
        with pytest.raises(StateError, match="torques must be a finite"):
            model.integrate_rk4(q, qdot, torques, STEP_S, lag=lag)
