"""swim-primitives flows: the summary numbers against computations from the library arrays, and clear errors."""
import json

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import simpson

from swim_model.vehicle import coriolis_from_mass
from swim_planner.cli import main
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitives import cruise_mean_speed_m_s

CRUISE = "constrained/cruise/E0.05"


def _mean(values, time_s):
    return float(simpson(values, x=time_s) / (time_s[-1] - time_s[0]))


def _tangent_force(model, primitive, rows):
    """The fluid's force on the foil along the hub's tangent at F, from the mechanism alone: for the constrained
    vehicle Q2 is square, so Q2' f = M_rigid qddot + C_rigid qdot - B tau gives f."""
    s = model.symbolic
    rigid = ca.Function("rigid", [s.q, s.qdot], [s.rigid_mass, coriolis_from_mass(s.rigid_mass, s.q, s.qdot) @ s.qdot])
    lag = primitive.lag[rows] if primitive.lag is not None else [None] * len(primitive.q[rows])
    out = []
    for q, qdot, u, tau, z in zip(primitive.q[rows], primitive.qdot[rows], primitive.foil_acceleration[rows],
                                  primitive.torque[rows], lag):
        qddot, _ = model.shape_dynamics(q, qdot, u, z)
        mass, bias = (np.asarray(m) for m in rigid(q, qdot))
        q2 = model.foil_velocity_map(q)
        force = np.linalg.solve(q2.T, mass @ qddot + bias.reshape(-1) - np.concatenate([[0.0], tau]))
        out.append(force[:2] @ q2[:2, 0] / np.linalg.norm(q2[:2, 0]))
    return np.array(out)


def test_the_json_numbers_are_the_library_arrays(library, circulatory_library, model_for, capsys):
    assert main(["flows", CRUISE, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert circulatory_library.entry(CRUISE)["mean_speed_m_s"] == pytest.approx(
        report["circulatory"]["mean_speed_m_s"], rel=1e-12)
    for flow, lib in (("ideal", library), ("circulatory", circulatory_library)):
        numbers, primitive = report[flow], lib.get(CRUISE)
        model = model_for(primitive.spec, flow)
        rows = slice(0, 2 * primitive.spec.intervals + 1)   # one solved cycle
        time_s, q, qdot = primitive.time_s[rows], primitive.q[rows], primitive.qdot[rows]
        assert numbers["duration_s"] == pytest.approx(primitive.spec.duration_s / primitive.spec.cycles)
        assert numbers["mean_speed_m_s"] == cruise_mean_speed_m_s(primitive)
        assert numbers["heave_range_rad"] == [q[:, 1].min(), q[:, 1].max()]
        assert numbers["pitch_range_rad"] == [q[:, 2].min(), q[:, 2].max()]
        angles = [abs(model.angle_of_attack(a, b)) for a, b in zip(q, qdot)]
        assert numbers["angle_of_attack_p95_deg"] == pytest.approx(np.degrees(np.percentile(angles, 95)), rel=1e-9)
        power = np.sum(primitive.torque[rows] * qdot[:, 1:], axis=1)
        assert numbers["mean_power_w"] == pytest.approx(_mean(power, time_s), rel=1e-9, abs=1e-12)
        thrust = _tangent_force(model, primitive, rows)
        assert numbers["mean_thrust_n"] == pytest.approx(_mean(thrust, time_s), rel=1e-6, abs=1e-9)
    assert report["ideal"]["mean_circulatory_thrust_n"] == 0.0
    # the leading-edge suction parameter, by hand: A0 |u| = Q_eff - Omega (x_mid - x_3/4) (docs/flow_model.md, Sec. 2)
    assert report["ideal"]["leading_edge_suction_parameter_p95"] is None
    primitive = circulatory_library.get(CRUISE)
    model = model_for(primitive.spec, "circulatory")
    flow, rows = model.circulatory_flow, slice(0, 2 * primitive.spec.intervals + 1)
    p = flow.params
    suction = []
    for q, qdot, z in zip(primitive.q[rows], primitive.qdot[rows], primitive.lag[rows]):
        u, v, omega = model.foil_velocity_map(q) @ qdot
        normal = -(v + omega * flow.three_quarter_chord_x_m)
        effective = (1.0 - p.wagner_slow_gain - p.wagner_fast_gain) * normal + p.wagner_slow_gain * z[0] \
            + p.wagner_fast_gain * z[1]
        suction.append((effective - omega * (flow.mid_chord_x_m - flow.three_quarter_chord_x_m)) / np.hypot(u, v))
    suction = np.abs(suction)
    numbers = report["circulatory"]
    assert numbers["leading_edge_suction_parameter_p95"] == pytest.approx(np.percentile(suction, 95), rel=1e-9)
    past = (suction > p.critical_leading_edge_suction).astype(float)
    assert numbers["time_past_critical_suction"] == pytest.approx(_mean(past, primitive.time_s[rows]), abs=1e-12)
    assert 0.0 < numbers["time_past_critical_suction"] < 1.0


def test_an_id_missing_from_one_library_is_a_clear_error(tmp_path, capsys, rig, circulatory_library):
    output = tmp_path / "x.png"
    assert main(["flows", "constrained/cruise/E0.20", "--output", str(output)]) == 2
    assert "'constrained/cruise/E0.20' is not in the ideal library" in capsys.readouterr().err
    cruise_only = PrimitiveLibrary.create_or_open(tmp_path / "cruise_only", rig, flow_model="circulatory")
    cruise_only.add(circulatory_library.get(CRUISE))
    accelerate = "constrained/accelerate/E0.05"
    assert main(["flows", accelerate, "--circulatory-library", str(cruise_only.path), "--output", str(output)]) == 2
    assert f"'{accelerate}' is not in the circulatory library" in capsys.readouterr().err
    assert not output.exists()


def test_the_figure_is_written(tmp_path, capsys):
    output = tmp_path / "accelerate.png"
    assert main(["flows", "constrained/accelerate/E0.05", "--output", str(output)]) == 0
    assert f"wrote {output}" in capsys.readouterr().out
    assert output.stat().st_size > 30_000
