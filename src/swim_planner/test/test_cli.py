"""swim-primitives: list, show, plot, and clear errors."""
import json

from swim_planner.cli import main
from swim_planner.primitives import CONVERGED_STATUSES


def test_list_shows_every_primitive(library, capsys):
    assert main(["list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1 + len(library)
    assert all(line.split()[-1] in CONVERGED_STATUSES for line in lines[1:])


def test_show_reports_the_manifest_and_the_states(library, capsys):
    assert main(["show", "constrained/cruise/E0.05"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["index_j"] == library.entry("constrained/cruise/E0.05")["index_j"]
    assert shown["start_q"] == library.get("constrained/cruise/E0.05").q[0].tolist()


def test_plot_writes_a_figure(tmp_path):
    output = tmp_path / "cruise.png"
    assert main(["plot", "constrained/cruise/E0.10", "--output", str(output)]) == 0
    assert output.stat().st_size > 20_000


def test_errors_are_one_clear_line(tmp_path, capsys):
    assert main(["show", "no/such"]) == 2
    assert "no primitive 'no/such'" in capsys.readouterr().err
    assert main(["list", str(tmp_path)]) == 2
    assert "no primitive library" in capsys.readouterr().err
    assert main(["build", str(tmp_path / "x"), "--only", "no/such"]) == 2
    assert "unknown primitive ids: no/such" in capsys.readouterr().err


def test_compare_sets_the_papers_method_beside_ours(library, capsys):
    assert main(["compare", "constrained/cruise/E0.05", "--evaluations", "400"]) == 0
    report = json.loads(capsys.readouterr().out)
    spec = library.spec("constrained/cruise/E0.05")
    assert report["collocation"]["index_j"] == library.entry("constrained/cruise/E0.05")["index_j"] / spec.cycles
    assert report["paper_method"]["index_j"] < report["collocation"]["index_j"]
    assert abs(report["paper_method"]["energy_error_j"]) > 0.0
    assert main(["compare", "free/cruise/R0.43/E0.05"]) == 2
    assert "constrained cruises and accelerates only" in capsys.readouterr().err


def test_a_build_refuses_a_library_of_the_other_flow_model(library, rig, tmp_path, capsys):
    from swim_planner.library import PrimitiveLibrary
    PrimitiveLibrary.create_or_open(tmp_path / "ideal", rig).add(library.get("constrained/cruise/E0.05"))
    assert main(["build", str(tmp_path / "ideal"), "--flow", "circulatory", "--only", "constrained/cruise/E0.05"]) == 2
    assert "holds primitives of the ideal flow model, not the circulatory one" in capsys.readouterr().err
    assert PrimitiveLibrary.load(tmp_path / "ideal", rig).ids() == ["constrained/cruise/E0.05"]


def test_a_circulatory_build_stores_the_flow_model_lag_states_speed_and_gains(rig, tmp_path, capsys):
    """One circulatory cruise built end to end, then listed and shown from the library it was written to."""
    from swim_planner.library import MANIFEST, PrimitiveLibrary
    from swim_planner.primitives import cruise_mean_speed_m_s
    cruise = "constrained/cruise/E0.05"
    assert main(["build", str(tmp_path / "lib"), "--flow", "circulatory", "--only", cruise, "--workers", "1"]) == 0
    assert json.loads((tmp_path / "lib" / MANIFEST).read_text())["flow_model"] == "circulatory"
    library = PrimitiveLibrary.load(tmp_path / "lib", rig, "circulatory")
    primitive = library.get(cruise)
    assert primitive.lag.shape == (len(primitive.time_s), 2) and primitive.gains is not None
    assert library.entry(cruise)["mean_speed_m_s"] == cruise_mean_speed_m_s(primitive) > 0.0
    capsys.readouterr()
    assert main(["list", str(tmp_path / "lib")]) == 0
    assert cruise in capsys.readouterr().out
