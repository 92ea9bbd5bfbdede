"""closed_loop_specs: which nodes with which parameters; the tracker's stale limit follows the plant's clock."""
from swim_bringup.system import LOCKSTEP_STALE_OVERRIDE, closed_loop_specs, config_dir, sim_mode


def _tracker(specs):
    return next(s for s in specs if s.executable == "tracker_node")


def test_lockstep_simulation_gets_the_long_stale_limit_and_real_time_plants_keep_theirs(tmp_path):
    assert sim_mode(config_dir() / "sim.yaml", ()) == "lockstep"          # the shipped sim.yaml
    assert LOCKSTEP_STALE_OVERRIDE in _tracker(closed_loop_specs(config_dir())).parameters
    for specs in (closed_loop_specs(config_dir(), ("mode:=realtime",)),
                  closed_loop_specs(config_dir(), plant="bridge"),
                  closed_loop_specs(config_dir(), tracker_overrides=("stale_after_periods:=7",))):
        assert LOCKSTEP_STALE_OVERRIDE not in _tracker(specs).parameters
    own = tmp_path / "sim.yaml"
    own.write_text("sim_node:\n  ros__parameters:\n    mode: realtime\n")
    assert sim_mode(own, ()) == "realtime" and sim_mode(own, ("mode:=lockstep",)) == "lockstep"
    assert sim_mode(tmp_path / "missing.yaml", ()) == "lockstep"          # sim_node's own default
