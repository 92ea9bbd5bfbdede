"""swim_planner.plots: the side-by-side traces against the force route of the equations of motion, and the figure."""
import casadi as ca
import numpy as np
import pytest
from scipy.integrate import simpson

from swim_model.vehicle import coriolis_from_mass
from swim_planner.plots import flow_traces, plot_flows, shown_samples

CRUISE, ACCELERATE = "constrained/cruise/E0.05", "constrained/accelerate/E0.05"


def _rigid_terms(model):
    """(q, qdot) -> (M_rigid, C_rigid qdot): the mechanism alone, without the fluid (hydrodynamics' force route)."""
    s = model.symbolic
    return ca.Function("rigid", [s.q, s.qdot], [s.rigid_mass, coriolis_from_mass(s.rigid_mass, s.q, s.qdot) @ s.qdot])


@pytest.fixture(scope="module")
def traces(library, circulatory_library, model_for):
    out = {}
    for flow, lib in (("ideal", library), ("circulatory", circulatory_library)):
        for primitive_id in (CRUISE, ACCELERATE):
            primitive = lib.get(primitive_id)
            model = model_for(primitive.spec, flow)
            out[flow, primitive_id] = primitive, model, flow_traces(primitive, model)
    return out


@pytest.mark.parametrize("flow", ["ideal", "circulatory"])
@pytest.mark.parametrize("primitive_id", [CRUISE, ACCELERATE])
def test_the_fluid_force_closes_the_mechanisms_equations(traces, flow, primitive_id):
    """M_rigid qddot + C_rigid qdot = B tau + Q2' f (paper eqs. 44-47): the fluid's force on the foil found by the
    traces (added mass, plus the circulatory force) is what the rigid mechanism needs besides the motors."""
    primitive, model, t = traces[flow, primitive_id]
    rows = shown_samples(primitive)
    rigid = _rigid_terms(model)
    lag = primitive.lag[rows] if primitive.lag is not None else [None] * len(t.time_s)
    worst, scale = 0.0, 0.0
    for k, (q, qdot, u, tau, z) in enumerate(zip(primitive.q[rows], primitive.qdot[rows],
                                                 primitive.foil_acceleration[rows], primitive.torque[rows], lag)):
        qddot, _ = model.shape_dynamics(q, qdot, u, z)
        mass, bias = (np.asarray(m) for m in rigid(q, qdot))
        mechanism = mass @ qddot + bias.reshape(-1)
        fluid = model.foil_velocity_map(q).T @ t.fluid_force[k]
        worst = max(worst, float(np.abs(mechanism - np.concatenate([[0.0], tau]) - fluid).max()))
        scale = max(scale, float(np.abs(mechanism).max()))
    assert worst < 1e-8 * max(scale, 1.0)


def test_the_hub_torque_changes_the_rigid_hub_momentum(traces):
    """The fluid's torque about the hub is the only torque on it: its integral over the accelerate is the change
    of the rigid bodies' hub momentum (M_rigid qdot, first entry), and its mean over a periodic cruise is zero."""
    for flow in ("ideal", "circulatory"):
        primitive, model, t = traces[flow, ACCELERATE]
        rigid = _rigid_terms(model)
        momentum = [float((np.asarray(rigid(primitive.q[k], primitive.qdot[k])[0]) @ primitive.qdot[k])[0])
                    for k in (0, -1)]
        impulse = float(simpson(t.hub_torque_n_m, x=t.time_s))
        assert impulse == pytest.approx(momentum[1] - momentum[0], rel=1e-3, abs=1e-6)
        _, _, cruise = traces[flow, CRUISE]
        peak = float(np.abs(cruise.hub_torque_n_m).max())
        assert abs(float(simpson(cruise.hub_torque_n_m, x=cruise.time_s))) < 1e-3 * peak * cruise.time_s[-1]


def test_a_cruise_shows_one_solved_cycle(traces):
    primitive, _, t = traces["circulatory", CRUISE]
    assert t.time_s[-1] == pytest.approx(primitive.spec.solved_duration_s)
    assert t.speed_m_s[0] == pytest.approx(t.speed_m_s[-1], abs=1e-6)   # periodic


def test_the_figure_is_written(traces, tmp_path):
    output = tmp_path / "flows.png"
    plot_flows([traces["ideal", CRUISE][2], traces["circulatory", CRUISE][2]], CRUISE, output)
    assert output.stat().st_size > 30_000
