"""The Python module against published values, closed forms and the `wbm` command (issue #18).

Run by `make test` (ctest label python) with PYTHONPATH=<build>/python and WBM_CLI=<build>/cli/wbm.
"""
import csv
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import wbm

SCENES = Path(__file__).resolve().parents[2] / "reproduce" / "scenes"
EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenes"


def test_db6_connection_coefficients_match_beylkin_1992():
    # r_l = Γ^{0,1}[−l]: −272/365, 53/365, −16/1095, −1/2920 [Beylkin 1992, M = 3].
    g = wbm.connection_coefficients("db6", 0, 1)
    at = lambda k: g["values"][k - g["first_shift"]]
    for l, r in zip(range(1, 5), [-272 / 365, 53 / 365, -16 / 1095, -1 / 2920]):
        assert at(-l) == pytest.approx(r, abs=1e-14)
    assert at(0) == pytest.approx(0.0, abs=1e-14)


def test_rod_first_frequency_is_the_published_1297_5_hz():
    # 20 elements, E = 210 GPa, ρ = 7800 kg/m³, L = 1 m [Laxalde & Legrand 2011, Sec. 5.1].
    rod = wbm.rod(210e9, 7800.0, 1e-4, 1.0, 20)
    assert rod.dofs == 20
    assert wbm.natural_frequencies_hz(rod)[0] == pytest.approx(1297.5, abs=0.5)


def test_linear_oscillator_matches_the_closed_form_amplitude():
    # m ü + c u̇ + k u = F cos ωt: amplitude F / |k − mω² + iωc|; Fourier coefficients
    # {1, cos 2πτ, sin 2πτ, …}, so the amplitude is √(a₁² + a₂²).
    m, c, k, force, f = 2.0, 6.0, 8e4, 10.0, 25.0
    system = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    basis = wbm.TimeBasis("fourier", 8)
    s = wbm.solve(system, 0, force, f, [], basis, basis)
    assert s["converged"] and s["status"] == "converged"
    w = 2 * math.pi * f
    exact = force / abs(complex(k - m * w * w, w * c))
    a = s["coefficients"]
    assert a.shape == (1, 8)
    assert math.hypot(a[0, 1], a[0, 2]) == pytest.approx(exact, rel=1e-12)


def test_a_rigid_stop_gives_a_flat_haar_plateau():
    # Haar trial functions are constant on each cell: in contact the tip sits at g0 exactly
    # (the Signorini conditions hold at the instants, and between them nothing moves).
    rod = wbm.rod(70e9, 2700.0, 25e-4, 1.0, 25, beta=1e-4)
    gap = 1e-3
    trial, weighting = wbm.TimeBasis("haar", 64), wbm.TimeBasis("fourier", 64)
    s = wbm.solve(rod, 24, 250e3, 150.0, [(24, wbm.RigidStop(gap))], trial, weighting)
    assert s["converged"], s["message"]
    assert s["contact_force_samples"].shape == (1, 64)
    tau = np.arange(1024) / 1024
    u = wbm.evaluate(trial, s["coefficients"], tau)
    assert u.shape == (25, 1024)
    assert u[24].max() == pytest.approx(gap, abs=1e-12 * gap)
    assert np.count_nonzero(np.abs(u[24] - gap) < 1e-12 * gap) > 16  # a plateau, not a touch


def test_run_scene_equals_the_wbm_command(tmp_path):
    # The CSV files of `wbm run` hold "%.17g" values: the same numbers as the module returns.
    scene = SCENES / "jl14_case1.toml"
    subprocess.run([os.environ["WBM_CLI"], "run", str(scene), "-o", str(tmp_path), "-q"], check=True)
    with open(tmp_path / "displacement.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, values = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
    result = wbm.run_scene(str(scene))
    assert result["converged"]
    table = result["tables"]["displacement.csv"]
    assert list(table.keys()) == header
    for j, name in enumerate(header):
        np.testing.assert_array_equal(table[name], values[:, j])


def test_result_mat_reads_with_scipy_and_equals_the_csv_files(tmp_path):
    # [output] formats = ["csv", "mat"]: result.mat (matio, MAT 5) read by an independent reader,
    # scipy.io.loadmat; every column equals its CSV column, units and headers come along, and a
    # massless contact node (issue #18) is in it like any DOF.
    scipy_io = pytest.importorskip("scipy.io")
    text = (EXAMPLES / "massless_contact_node.toml").read_text()
    text = text.replace("[output]\n", '[output]\nformats = ["csv", "mat"]\n')
    scene = tmp_path / "massless.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    subprocess.run([os.environ["WBM_CLI"], "run", str(scene), "-o", str(out), "-q"], check=True)
    mat = scipy_io.loadmat(out / "result.mat", simplify_cells=True)
    assert bool(mat["wbm"]["converged"]) is True
    assert mat["wbm"]["scene"] == "massless"
    files = list(mat["wbm"]["files"])
    assert "displacement.csv" in files and "contact_force.csv" in files
    for file in files:
        with open(out / file, newline="") as f:
            rows = list(csv.reader(f))
        header, values = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
        table = mat[Path(file).stem]
        assert list(table["columns"]) == header
        for j, column in enumerate(header):
            name, unit = column[: column.rindex(" [")], column[column.rindex("[") + 1 : -1]
            field = name.replace("-", "_")
            np.testing.assert_array_equal(np.atleast_1d(table[field]), values[:, j])
            assert table["units"][field] == unit
    assert set(mat["displacement"]) >= {"u_x", "u_xc", "tau", "time"}
    assert mat["displacement"]["units"]["u_xc"] == "m"


def test_a_scene_from_a_path_a_string_or_a_dict_is_the_same_scene():
    scene = SCENES / "jl14_case1.toml"
    from_path = wbm.run_scene(scene)  # os.PathLike
    from_text = wbm.run_scene(scene.read_text())
    from_dict = wbm.run_scene(wbm.scene_json(str(scene)))
    tip = "u_node25 [m]"  # the Case 1 rod's 25 elements, observed at the tip
    u = from_path["tables"]["displacement.csv"][tip]
    assert u.ndim == 1 and u.size > 0
    for other in (from_text, from_dict):
        np.testing.assert_array_equal(other["tables"]["displacement.csv"][tip], u)


def test_bad_arguments_raise_with_the_message():
    with pytest.raises(ValueError, match="basis 'morlet' is unknown; valid names: fourier"):
        wbm.TimeBasis("morlet", 8)
    with pytest.raises(ValueError, match="Haar"):
        wbm.connection_coefficients("haar", 0, 1)
    with pytest.raises(ValueError, match="family 'db7x' is unknown"):
        wbm.connection_coefficients("db7x", 0, 1)
    with pytest.raises(ValueError, match="not symmetric"):
        wbm.MechanicalSystem([[1.0, 0.0], [0.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]], [[2.0, -1.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match=r"<string>:3: forcing.amplitude"):
        wbm.run_scene('structure = { mass = 1.0, stiffness = 4e4 }\n\nforcing = { amplitude = "ten", frequency_hz = 5.0 }\n')
    with pytest.raises(ValueError, match="neither an existing scene file nor TOML text"):
        wbm.run_scene("no-such-scene.toml")
    with pytest.raises(ValueError, match="formulation 'galerkin' is unknown"):
        basis = wbm.TimeBasis("fourier", 8)
        wbm.solve(wbm.MechanicalSystem([[1.0]], [[0.0]], [[1.0]]), 0, 1.0, 1.0, [], basis, basis, formulation="galerkin")
    with pytest.raises(RuntimeError, match="a rigid stop has no force law"):  # std::logic_error
        wbm.RigidStop(1e-3).force(0.0)
