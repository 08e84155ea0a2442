import json

import pytest

from mrclutch.cli.main import main


def test_torque_json_shape(capsys):
    assert main(["torque", "--preset", "paper", "--current", "0:7:1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["current_A"] for p in out["points"]] == [0, 1, 2, 3, 4, 5, 6, 7]
    t = [p["torque_N_m"] for p in out["points"]]
    assert t == sorted(t) and t[0] == pytest.approx(out["off_state_torque_N_m"])
    assert out["drag_damping_N_m_s"] > 0 and out["speed_rpm"] == 530


def test_torque_plot_and_field_plot(tmp_path, capsys):
    png = tmp_path / "t.png"
    assert main(["torque", "--current", "0,2,4", "--plot", str(png)]) == 0
    assert png.stat().st_size > 1000
    fld = tmp_path / "f.png"
    assert main(["field", "--current", "4", "--size-mm", "0.5", "--plot", str(fld)]) == 0
    assert fld.stat().st_size > 1000


@pytest.mark.parametrize(
    "args",
    [
        ["torque", "--current", "7:0:1"],
        ["torque", "--current", "0:7:0"],
        ["torque", "--current", "nan"],
        ["torque", "--current", "a:b"],
        ["torque", "--method", "magic"],
        ["field", "--current", "inf", "--plot", "x.png"],
    ],
)
def test_bad_input_one_line_exit_2(args, tmp_path, monkeypatch, capsys):
    """Through main() from a scratch folder, in this process (a fresh process's bad input:
    test_cli_haptic's test_subprocess_bad_input_no_traceback)."""
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_torque_both_methods_chart_and_error(tmp_path, capsys):
    """Issue 4: the default model (the network) against the FEM on the paper preset,
    0-7 A, chart and largest error (measured: within 1 %)."""
    import json

    from mrclutch.cli.main import main

    png = tmp_path / "both.png"
    args = ["torque", "--method", "both", "--current", "0,2,4,7", "--plot", str(png), "--json"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert [p["current_A"] for p in data["fem"]["points"]] == [0.0, 2.0, 4.0, 7.0]
    c = [p["torque_N_m"] for p in data["network"]["points"]]
    f = [p["torque_N_m"] for p in data["fem"]["points"]]
    assert data["max_torque_error_rel"] == max(
        abs(a / b - 1) for a, b in zip(c[1:], f[1:], strict=True)
    )
    # issue 12 aims at 2 % on the preset; the network is +1.57 % at 7 A (docs/magnetics.md,
    # "The paper preset")
    assert data["max_torque_error_rel"] <= 0.02
    assert png.stat().st_size > 1000


def test_torque_reports_flux_linkage_and_inductance(capsys):
    """λ(I) from the circuit rises with current and flattens as the iron saturates: its
    slope (the incremental inductance) is the printed L and falls with current; L at 0 A
    equals the centred difference of λ at small currents."""
    import numpy as np

    assert main(["torque", "--preset", "paper", "--current", "0:7:0.5", "--method", "circuit",
                 "--json"]) == 0  # fmt: skip
    d = json.loads(capsys.readouterr().out)
    lam, ind = np.array(d["flux_linkage_Wb"]), np.array(d["inductance_H"])
    cur = np.array([p["current_A"] for p in d["points"]])
    assert np.all(np.diff(lam) > 0) and np.all(np.diff(ind) < 0)
    mid = np.gradient(lam, cur)[1:-1]
    assert ind[1:-1] == pytest.approx(mid, rel=0.15)  # a 0.5 A step: a coarse difference


def test_torque_by_the_network_reports_the_networks_flux_linkage(capsys):
    """With --method network, λ(I) and L(I) are the network's (labelled so), not the
    circuit's: the same numbers as magnetics.network.flux_linkage."""
    import numpy as np

    from geometry.params import preset
    from geometry.section import build_section
    from magnetics.network import flux_linkage, network_from_regions

    assert main(["torque", "--preset", "paper", "--current", "1,4", "--method", "network",
                 "--json"]) == 0  # fmt: skip
    d = json.loads(capsys.readouterr().out)
    assert d["flux_linkage_method"] == "network"
    net = network_from_regions(build_section(preset("paper")).table)
    lam, ind = flux_linkage(net, net.turns[:, None] * np.array([1.0, 4.0]))
    np.testing.assert_allclose(d["flux_linkage_Wb"], lam[0], rtol=1e-12)
    np.testing.assert_allclose(d["inductance_H"], ind[0], rtol=1e-12)
    assert main(["torque", "--preset", "paper", "--current", "1", "--method", "network"]) == 0
    assert "L_inc_mH (network)" in capsys.readouterr().out
