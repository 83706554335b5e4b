"""The Python module against published values, closed forms and the `wbm` command (issue #18).

Run by `make test` (ctest label python) with PYTHONPATH=<build>/python and WBM_CLI=<build>/cli/wbm.
"""
import csv
import json
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
    # The keys of result.json's diagnostics.solution (one serializer), plus the arrays.
    assert {"message", "newton", "path", "relative_residual", "backward_error", "max_penetration_m",
            "condition_number"} <= s.keys()
    assert 0.0 <= s["backward_error"] <= s["relative_residual"]
    assert s["newton"]["status"] == "converged" and s["newton"]["tolerance"] > 0.0
    assert s["dropped_harmonics_residual"] is None  # no harmonic selection: not finite, written as null
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
    # One outcome protocol (issue #41): the same status and flag as the command's result.json.
    with open(tmp_path / "result.json") as f:
        written = json.load(f)
    assert result["status"] == written["diagnostics"]["status"] == "converged"
    assert written["converged"] is written["diagnostics"]["converged"] is True
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


def test_trace_response_follows_the_closed_form_below_the_stop():
    # A stop 1 m away is never met: the branch is the linear oscillator's F/|k − mω² + iωc|, and
    # every point is stable (largest Floquet multiplier e^{−ζω_n T} < 1).
    s = wbm.MechanicalSystem(mass=np.array([[2.0]]), damping=np.array([[6.0]]), stiffness=np.array([[8e4]]))
    fourier = wbm.TimeBasis("fourier", 8)
    curve = wbm.trace_response(s, 0, 10.0, (5.0, 55.0), [(0, wbm.LinearPenalty(1e6, 1.0))], fourier, fourier,
                               max_frequency_step_hz=1.0, samples=1024)
    assert curve["converged"], curve["message"]
    f = curve["frequency_hz"]
    assert f.ndim == 1 and f.size >= 50 and curve["amplitude"].shape == f.shape
    inside = f <= 55.0
    w = 2 * math.pi * f[inside]
    exact = 10.0 / np.abs(8e4 - 2.0 * w**2 + 1j * 6.0 * w)
    np.testing.assert_allclose(curve["amplitude"][inside], exact, rtol=1e-5)
    assert curve["stable"].all() and (curve["max_floquet_multiplier"] < 1.0).all()
    assert curve["folds_hz"] == []
    # The same stop rigid: each point's exact orbit (no impact) is the linear one, and its largest
    # multiplier is |e^{λT}| = e^{−(c/2m)/f} in closed form.
    rigid = wbm.trace_response(s, 0, 10.0, (5.0, 55.0), [(0, wbm.RigidStop(1.0))], fourier, fourier,
                               max_frequency_step_hz=5.0)
    assert rigid["converged"], rigid["message"]
    assert rigid["stability_available"].all() and (rigid["shooting_distance"] < 1e-9).all()
    np.testing.assert_allclose(rigid["max_floquet_multiplier"], np.exp(-1.5 / rigid["frequency_hz"]), rtol=1e-9)


def test_trace_response_gives_each_fold_its_own_amplitude():
    # 1 kg on 40 kN/m, C = 5 M, 5 N, a stop 100 x stiffer 2 mm away (examples/scenes/
    # stiff_stop_continuation.toml). The jump-up fold is the grazing orbit, the linear response of
    # amplitude g: (k − mω²)² + (cω)² = (F/g)². Its amplitude is the gap, while the nearest point in
    # frequency may lie on the upper sheet (issue #35). Sampled at midpoints the stop's corner stalls
    # the continuation, and the message names the way out.
    s = wbm.MechanicalSystem(mass=np.array([[1.0]]), damping=np.array([[5.0]]), stiffness=np.array([[4e4]]))
    fourier = wbm.TimeBasis("fourier", 64)
    stalled = wbm.trace_response(s, 0, 5.0, (15.0, 60.0), [(0, wbm.LinearPenalty(4e6, 2e-3))], fourier, fourier,
                                 stability=False)
    assert not stalled["converged"] and "contact_quadrature" in stalled["message"]
    with pytest.raises(ValueError, match="contact_quadrature"):
        wbm.trace_response(s, 0, 5.0, (15.0, 60.0), [(0, wbm.LinearPenalty(4e6, 2e-3))], fourier, fourier,
                           contact_quadrature="trapezoid")
    curve = wbm.trace_response(s, 0, 5.0, (15.0, 60.0), [(0, wbm.LinearPenalty(4e6, 2e-3))], fourier, fourier,
                               stability=False, contact_quadrature="cell-average")
    assert curve["converged"], curve["message"]
    assert len(curve["folds_hz"]) == len(curve["fold_amplitudes"]) == 2
    b = 2 * 4e4 - 25.0
    grazing = math.sqrt(0.5 * (b + math.sqrt(b * b - 4 * (4e4**2 - (5.0 / 2e-3) ** 2)))) / (2 * math.pi)
    lower = int(np.argmin(curve["folds_hz"]))
    assert abs(curve["folds_hz"][lower] - grazing) < 0.01
    assert curve["fold_amplitudes"][lower] == pytest.approx(2e-3, rel=1e-2)
    assert curve["fold_amplitudes"][1 - lower] > 1.5 * curve["fold_amplitudes"][lower]


def test_nonlinear_mode_equals_the_scene_backbone_and_the_linear_mode():
    # The 2-DOF chain of examples/scenes/two_dof_nnm.toml: below contact onset the frequency is the
    # linear one, √(k (3 − √5)/2 / m)/2π; the whole backbone equals the one `wbm run` writes.
    m = np.eye(2)
    k = np.array([[2000.0, -1000.0], [-1000.0, 1000.0]])
    s = wbm.MechanicalSystem(mass=m, damping=np.zeros((2, 2)), stiffness=k)
    mode = wbm.nonlinear_mode(s, [(1, 1e-3)], (0.5, 3.0), harmonics=8, samples=64)
    assert mode["converged"], mode["message"]
    linear = math.sqrt(1000.0 * (3.0 - math.sqrt(5.0)) / 2.0) / (2.0 * math.pi)
    assert mode["linear_frequency_hz"] == pytest.approx(linear, rel=1e-12)
    # The levels before the branch first turns back in energy (its first fold, at contact onset).
    before = np.arange(np.argmax(np.diff(mode["energy"]) < 0.0) + 1)
    assert before.size >= 5
    np.testing.assert_allclose(mode["frequency_hz"][before], linear, rtol=1e-10)
    assert mode["frequency_hz"][-1] > 1.2 * linear  # the stop stiffens the mode
    scene = wbm.run_scene(EXAMPLES / "two_dof_nnm.toml")
    table = scene["tables"]["backbone.csv"]
    np.testing.assert_array_equal(table["energy [-]"], mode["energy"])
    np.testing.assert_array_equal(table["frequency [Hz]"], mode["frequency_hz"])
    np.testing.assert_array_equal(table["first_mode_share [-]"], mode["first_mode_share"])
    # Below contact the linear first mode holds all the energy; shares never exceed 1 together.
    np.testing.assert_allclose(mode["first_mode_share"][before], 1.0, rtol=0, atol=1e-12)
    assert (mode["first_mode_share"] + mode["other_share"] <= 1.0 + 1e-12).all()
    assert mode["first_mode_share"][-1] < 1.0 - 1e-3


def plastic_impact_orbit(tau, m, k, c, amplitude, f, gap):
    """Issue #16's closed form: the mass rests on the stop while F cos(wt) >= k g0, leaves it at
    w t1 = arccos(k g0 / F) and flies freely until its first return to g0 (bisection), u(tau)."""
    w, wn = 2.0 * math.pi * f, math.sqrt(k / m)
    zeta = c / (2.0 * math.sqrt(k * m))
    wd = wn * math.sqrt(1.0 - zeta ** 2)
    amp = amplitude / complex(k - m * w ** 2, w * c)
    t1 = math.acos(k * gap / amplitude) / w
    a = gap - (amp * np.exp(1j * w * t1)).real
    b = (zeta * wn * a - (1j * w * amp * np.exp(1j * w * t1)).real) / wd

    def flight(t):
        s = t - t1
        return (amp * np.exp(1j * w * t)).real + np.exp(-zeta * wn * s) * (a * np.cos(wd * s) + b * np.sin(wd * s))

    grid = t1 + np.linspace(1e-2, 1.25, 200001) / f  # the mass leaves tangentially: skip rounding at t1
    above = np.flatnonzero(flight(grid) > gap)
    lo, hi = grid[above[0] - 1], grid[above[0]]
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if flight(mid) < gap else (lo, mid)
    t = np.asarray(tau) / f
    t = np.where(t < t1, t + 1.0 / f, t)
    return np.where(t <= lo, flight(t), gap)


def test_haar_impact_converges_to_the_plastic_impact_orbit_in_closed_form():
    # Issue #16's point mass (1 kg, 10 Hz, zeta = 0.05, 8 Hz, k g0 / F = 1/2) with e = 0: the cell
    # values at the cells' midpoints converge to the closed form at second order.
    k = (2.0 * math.pi * 10.0) ** 2
    c = 0.1 * math.sqrt(k)
    s = wbm.MechanicalSystem(mass=np.eye(1), damping=np.array([[c]]), stiffness=np.array([[k]]))
    errors = []
    for cells in (64, 256):
        r = wbm.haar_impact(s, 0, 10.0, 8.0, [(0, 5.0 / k)], cells=cells)
        assert r["converged"], r["message"]
        assert r["displacement"].shape == (1, cells) and r["impulses"].shape == (1, cells)
        exact = plastic_impact_orbit(r["tau"], 1.0, k, c, 10.0, 8.0, 5.0 / k)
        errors.append(np.sqrt(np.mean((r["displacement"][0] - exact) ** 2) / np.mean(exact ** 2)))
        assert r["penetration"] <= 1e-12 and (r["impulses"] >= 0.0).all()
    assert errors[1] < 1e-4
    assert math.log(errors[0] / errors[1], 4.0) == pytest.approx(2.0, abs=0.3)
    with pytest.raises(ValueError, match="restitution"):
        wbm.haar_impact(s, 0, 10.0, 8.0, [(0, 5.0 / k)], restitution=1.5)
    with pytest.raises(ValueError, match="cells"):
        wbm.haar_impact(s, 0, 10.0, 8.0, [(0, 5.0 / k)], cells=4)


def test_basis_mode_is_the_linear_mode_below_contact_in_each_basis():
    # The 2-DOF chain of examples/scenes/two_dof_nnm.toml. Below contact onset Fourier gives the
    # linear frequency (closed form) and Haar the central-difference scheme's, f (pi/M)/sin(pi/M);
    # above onset the stop stiffens the mode in both.
    s = wbm.MechanicalSystem(mass=np.eye(2), damping=np.zeros((2, 2)),
                             stiffness=np.array([[2000.0, -1000.0], [-1000.0, 1000.0]]))
    linear = math.sqrt(1000.0 * (3.0 - math.sqrt(5.0)) / 2.0) / (2.0 * math.pi)
    for name, factor, offset in (("fourier", 1.0, 0.0), ("haar", (math.pi / 32) / math.sin(math.pi / 32), 0.5)):
        mode = wbm.basis_mode(s, [(1, 1e-3)], (0.5, 1.5), wbm.TimeBasis(name, 32))
        assert mode["converged"], mode["message"]
        assert mode["sample_offset"] == offset and mode["samples"] == 32
        assert mode["unknowns"] == 2 * 32 + 1 + 32 + 1
        assert mode["linear_frequency_hz"] == pytest.approx(linear, rel=1e-12)
        # The levels before the branch first turns back in energy (its first fold, at contact onset).
        before = np.arange(np.argmax(np.diff(mode["energy"]) < 0.0) + 1)
        below = before[mode["energy"][before] < 1.0]
        assert below.size >= 5
        np.testing.assert_allclose(mode["frequency_hz"][below], linear * factor, rtol=1e-10)
        assert mode["frequency_hz"][-1] > 1.01 * linear * factor
        assert (mode["max_penetration"] <= 1e-9).all()
    with pytest.raises(ValueError, match="DB4"):
        wbm.basis_mode(s, [(1, 1e-3)], (0.5, 1.5), wbm.TimeBasis("db4", 32))
    with pytest.raises(ValueError, match="samples = 8"):
        wbm.basis_mode(s, [(1, 1e-3)], (0.5, 1.5), wbm.TimeBasis("haar", 32), samples=8)


def test_nonlinear_mode_stability_is_the_linear_modes_below_contact():
    # The same chain with stability=True: below contact every level is the linear mode, an exact orbit
    # without impacts, stable with |mu| = 1 at the linear frequency (closed form); above it every level
    # has a verdict on this chain (test_impact_modes checks the verdicts against the flow).
    s = wbm.MechanicalSystem(mass=np.eye(2), damping=np.zeros((2, 2)),
                             stiffness=np.array([[2000.0, -1000.0], [-1000.0, 1000.0]]))
    mode = wbm.nonlinear_mode(s, [(1, 1e-3)], (0.5, 1.5), harmonics=8, samples=64, stability=True)
    assert mode["converged"], mode["message"]
    linear = math.sqrt(1000.0 * (3.0 - math.sqrt(5.0)) / 2.0) / (2.0 * math.pi)
    below = np.flatnonzero(np.asarray(mode["impacts"]) == 0)
    assert below.size >= 5
    assert all(mode["stable"][i] for i in below)
    np.testing.assert_allclose(np.asarray(mode["max_floquet_multiplier"])[below], 1.0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.asarray(mode["exact_frequency_hz"])[below], linear, rtol=1e-9)
    assert len(mode["stable"]) == len(mode["energy"])
    with pytest.raises(ValueError, match="stability=True with penalty_stiffness"):
        wbm.nonlinear_mode(s, [(1, 1e-3)], (0.5, 1.5), harmonics=8, samples=64, penalty_stiffness=1e6,
                           stability=True)


def test_solve_with_several_loads_superposes_closed_forms():
    # 10 N cos ωt + 4 N cos(2ωt + π/4) + a constant 3 N on one oscillator (docs: loads).
    s = wbm.MechanicalSystem(mass=np.array([[2.0]]), damping=np.array([[6.0]]), stiffness=np.array([[8e4]]))
    fourier = wbm.TimeBasis("fourier", 8)
    r = wbm.solve(s, 0, 10.0, 25.0, [], fourier, fourier, loads=[(0, 4.0, math.pi / 4, 2), (0, 3.0, 0.0, 0)])
    assert r["converged"]
    tau = np.linspace(0.0, 1.0, 16, endpoint=False)
    u = wbm.evaluate(fourier, r["coefficients"], tau)[0]
    w = 2 * math.pi * 25.0
    exact = sum(np.real(a * np.exp(1j * (phi + 2 * math.pi * h * tau)) / (8e4 - 2.0 * (h * w) ** 2 + 6j * h * w))
                for a, phi, h in ((10.0, 0.0, 1), (4.0, math.pi / 4, 2), (3.0, 0.0, 0)))
    np.testing.assert_allclose(u, exact, rtol=0, atol=1e-12 * np.abs(exact).max())
    with pytest.raises(ValueError, match=r"HarmonicForcing.more\[0\].harmonic = -1"):
        wbm.solve(s, 0, 10.0, 25.0, [], fourier, fourier, loads=[(0, 1.0, 0.0, -1)])


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


def test_harmonic_selection_keeps_only_the_listed_harmonics():
    # Linear oscillator: the closed-form response is harmonic 1 alone, so keeping [1] loses
    # nothing. Fourier M = 8 ordering: 1, cos 2πτ, sin 2πτ, cos 4πτ, sin 4πτ, cos 6πτ, sin 6πτ, cos 8πτ.
    m, c, k, force, f = 2.0, 6.0, 8e4, 10.0, 25.0
    system = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    basis = wbm.TimeBasis("fourier", 8)
    s = wbm.solve(system, 0, force, f, [], basis, basis, harmonics=[1])
    assert s["converged"], s["message"]
    w = 2 * math.pi * f
    a = s["coefficients"]
    assert math.hypot(a[0, 1], a[0, 2]) == pytest.approx(force / abs(complex(k - m * w * w, w * c)), rel=1e-12)
    assert s["dropped_harmonics_residual"] == 0.0
    # A one-sided stop: odd harmonics only leave the mean and harmonic 2 out (exact zeros), and
    # the residual they would carry is reported, not hidden.
    stop = wbm.LinearPenalty(1e6, 1e-4)
    s = wbm.solve(system, 0, force, 32.0, [(0, stop)], basis, basis, harmonics=[1, 3])
    assert s["converged"], s["message"]
    assert s["max_contact_force_N"] > 0.0
    np.testing.assert_array_equal(s["coefficients"][0, [0, 3, 4, 7]], 0.0)
    assert s["dropped_harmonics_residual"] > 1e-3
    with pytest.raises(ValueError, match=r"harmonic 5 is outside \[0, 4\]"):
        wbm.solve(system, 0, force, f, [], basis, basis, harmonics=[1, 5])


def test_jenkins_loop_gives_griffins_loop_and_its_energy():
    # w = A cos θ drives a Jenkins element (k_t, F_s) with A > F_s/k_t: the slider slips once
    # the spring has travelled 2F_s/k_t after each reversal, and the loop encloses
    # 4 F_s (A − F_s/k_t) per cycle [Griffin 1980].
    kt, fs, a, n = 1e6, 0.5, 2e-6, 4096
    theta = 2.0 * np.pi * (np.arange(n) + 0.5) / n
    loop = wbm.jenkins_loop(kt, a * np.cos(theta), np.full(n, fs))
    assert loop["dissipated_energy"] == pytest.approx(4.0 * fs * (a - fs / kt), rel=1e-3)
    assert np.max(np.abs(loop["force"])) == pytest.approx(fs, rel=1e-15)
    assert loop["periods"] >= 2
    # The stick samples: from the reversal at θ = π, w = −A cos φ (θ = π + φ) travels A(1 − cos φ)
    # and the spring holds until that reaches 2F_s/k_t, φ < arccos(1 − 2F_s/(k_t A)): a third of
    # each half period here (2F_s/(k_t A) = 1/2).
    stick = np.arccos(1.0 - 2.0 * fs / (kt * a)) / np.pi
    assert stick == pytest.approx(1.0 / 3.0, rel=1e-12)
    assert loop["slipping_samples"] / n == pytest.approx(1.0 - stick, abs=3.0 / n)
    with pytest.raises(ValueError, match="slip_force"):
        wbm.jenkins_loop(kt, np.zeros(4), np.full(3, fs))


def _den_hartog_ratio(law, f0, r=1.5, dimension=256):
    """The 1-DOF oscillator m = 1 kg, f_n = 10 Hz, P = 1 N with `law` (slip force f0) solved by
    Fourier:Fourier at r = ω/ω_n: (max|x| / Den Hartog's amplitude, the solution). Den Hartog
    [1930]: (P/k) √((1/(1 − r²))² − (F0 U/P)²), U = tan(π/(2r))/r."""
    m, k, p = 1.0, (2.0 * math.pi * 10.0) ** 2, 1.0
    u = math.tan(math.pi / (2.0 * r)) / r
    exact = p / k * math.sqrt((1.0 / (1.0 - r * r)) ** 2 - (f0 * u / p) ** 2)
    system = wbm.MechanicalSystem([[m]], [[0.0]], [[k]])
    basis = wbm.TimeBasis("fourier", dimension)
    s = wbm.solve(system, 0, p, 10.0 * r, [(0, law)], basis, basis)
    assert s["converged"], s["message"]
    tau = np.arange(4096) / 4096
    return np.max(np.abs(basis.values(tau) @ s["coefficients"][0])) / exact, s


def test_a_jenkins_element_tends_to_den_hartogs_coulomb_amplitude():
    # m ẍ + k x + F0 sign ẋ = P cos ωt without stops [Den Hartog 1930]; the Jenkins element with
    # k_t = 1e4 k is within 3.5e-3 of it (its stick at each reversal, tests/solvers/test_friction.cpp).
    k, f0 = (2.0 * math.pi * 10.0) ** 2, 0.2
    ratio, s = _den_hartog_ratio(wbm.JenkinsLaw(tangential_stiffness=1e4 * k, friction_coefficient=f0, normal_load=1.0), f0)
    assert ratio == pytest.approx(1.0, abs=3.5e-3)
    assert s["max_contact_force_N"] == pytest.approx(f0, rel=1e-12)
    with pytest.raises(ValueError, match="friction_coefficient"):
        wbm.JenkinsLaw(tangential_stiffness=1e4 * k, friction_coefficient=-0.1, normal_load=1.0)


def test_a_jenkins_damper_branch_carries_stability_and_every_point_is_stable():
    # trace_response with stability=True and a Jenkins element (solvers/floquet.hpp: the monodromy
    # matrix carries the element's force perturbation): a viscously damped oscillator with Jenkins
    # friction under a constant normal load is incrementally passive, so no forced orbit is
    # unstable; at 5 Hz, where the slider slips over nearly the whole cycle, |μ| is nearly the free
    # oscillator's e^{−cT/2}.
    m, k = 1.0, (2.0 * math.pi * 10.0) ** 2
    c = 2.0 * 0.005 * math.sqrt(k * m)
    system = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    basis = wbm.TimeBasis("fourier", 33)
    law = wbm.JenkinsLaw(tangential_stiffness=1e3 * k, friction_coefficient=0.2, normal_load=1.0)
    curve = wbm.trace_response(system, 0, 1.0, (5.0, 20.0), [(0, law)], basis, basis, samples=256)
    assert curve["stable"].all() and curve["stability_available"].all()
    assert np.max(curve["max_floquet_multiplier"]) < 1.0
    assert curve["max_floquet_multiplier"][0] == pytest.approx(math.exp(-0.5 * c / (m * 5.0)), abs=1e-3)


def test_a_branch_in_the_friction_coefficient_meets_the_dampers_closed_forms():
    # trace_response with friction_coefficient=(from, to) at one frequency: the damper at its
    # resonance (ζ = 0.5 %, k_t = 1000 k, N = 1 N). While the slider slips the amplitude is the
    # first-harmonic balance (P − 4μN/π)/(cω); stuck at every instant (μN above k_t X) the mass
    # rides on k + k_t: X = P/(k + k_t − mω²). Ranges given the wrong way round are refused.
    m, k = 1.0, (2.0 * math.pi * 10.0) ** 2
    c, kt, omega = 2.0 * 0.005 * math.sqrt(k * m), 1e3 * k, 2.0 * math.pi * 10.0
    system = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    basis = wbm.TimeBasis("fourier", 65)
    law = wbm.JenkinsLaw(tangential_stiffness=kt, friction_coefficient=0.3, normal_load=1.0)
    # At the default Q = 256 the nonsmooth corrector stalls at the onset of full stick (a kink of
    # the sampled loop); the branch goes on there on stick/slip events ("never" stops instead).
    stalled = wbm.trace_response(system, 0, 1.0, 10.0, [(0, law)], basis, basis, stability=False,
                                 friction_coefficient=(0.1, 1.2), stick_slip_events="never")
    assert not stalled["converged"] and stalled["events"] == 0
    curve = wbm.trace_response(system, 0, 1.0, 10.0, [(0, law)], basis, basis, stability=False,
                               friction_coefficient=(0.1, 1.2))
    assert curve["converged"], curve["message"]
    assert curve["events"] > 0
    mu, amplitude = curve["friction_coefficient"], curve["amplitude"]
    assert mu[0] == 0.1 and mu[-1] == 1.2 and np.all(curve["frequency_hz"] == 10.0)
    slipping = mu < 0.6
    assert np.count_nonzero(slipping) > 10
    first_harmonic = (1.0 - 4.0 * mu[slipping] / math.pi) / (c * omega)
    assert np.max(np.abs(amplitude[slipping] / first_harmonic - 1.0)) < 1e-4
    assert amplitude[-1] == pytest.approx(1.0 / (k + kt - m * omega ** 2), rel=1e-9)
    with pytest.raises(ValueError, match="a branch in mu is at one frequency"):
        wbm.trace_response(system, 0, 1.0, (5.0, 20.0), [(0, law)], basis, basis, friction_coefficient=(0.1, 1.2))
    with pytest.raises(ValueError, match="is one frequency"):
        wbm.trace_response(system, 0, 1.0, 10.0, [(0, law)], basis, basis)
    with pytest.raises(ValueError, match='stick_slip_events = "sometimes" is not one of'):
        wbm.trace_response(system, 0, 1.0, 10.0, [(0, law)], basis, basis, friction_coefficient=(0.1, 1.2),
                           stick_slip_events="sometimes")


def test_a_normal_contact_at_rest_gives_the_constant_load_it_balances():
    # A point mass on springs k in x and y, pressed by a normal spring k_n of gap g < 0 and rubbing
    # along x through a Jenkins element whose slip force follows that spring, (dof, law, normal):
    # nothing forces y, so y rests where k y + k_n (y − g) = 0 and the spring's force is the
    # closed form N = −g k k_n / (k + k_n). The x response then equals that of the constant load N
    # (another code path: no normal contact at all), to rounding.
    m, k, kn, g, kt, mu = 1.0, (2.0 * math.pi * 10.0) ** 2, 2e4, -5e-5, 2e4, 0.3
    n_closed = -g * k * kn / (k + kn)
    c = 2.0 * 0.02 * math.sqrt(k * m)
    both = wbm.MechanicalSystem(np.diag([m, m]), np.diag([c, c]), np.diag([k, k]))
    basis = wbm.TimeBasis("fourier", 65)
    varying = wbm.solve(both, 0, 1.0, 12.0, [(1, wbm.LinearPenalty(kn, g)),
                                             (0, wbm.JenkinsLaw(tangential_stiffness=kt, friction_coefficient=mu,
                                                                normal_load=0.0), 0)], basis, basis)
    assert varying["converged"], varying["message"]
    one = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    constant = wbm.solve(one, 0, 1.0, 12.0, [(0, wbm.JenkinsLaw(tangential_stiffness=kt, friction_coefficient=mu,
                                                                  normal_load=n_closed))], basis, basis)
    assert constant["converged"], constant["message"]
    x = varying["coefficients"][0]
    assert np.max(np.abs(x - constant["coefficients"][0])) < 1e-9 * np.max(np.abs(x))
    assert varying["max_contact_force_N"] == pytest.approx(n_closed, rel=1e-9)  # the normal spring's
    with pytest.raises(ValueError, match="ContactPoint.normal = 0"):
        wbm.solve(one, 0, 1.0, 12.0, [(0, wbm.JenkinsLaw(tangential_stiffness=kt, friction_coefficient=mu,
                                                           normal_load=0.0), 0)], basis, basis)


def test_exact_coulomb_friction_on_a_prestressed_rigid_plane_rubs_under_its_reaction():
    # A 2D contact, (dof, CoulombFriction, normal) with the normal a RigidStop: a point mass on
    # springs k in x and y whose plane sits at y = g < 0, so it holds y at g with the reaction
    # N = −k g (statics, at every instant). The x response is then that of a constant load N, to
    # rounding (Fourier: the instants' quadrature is exact), and the plane's impulses are N.
    m, k, g, mu = 1.0, (2.0 * math.pi * 10.0) ** 2, -1e-4, 0.3
    c = 2.0 * 0.02 * math.sqrt(k * m)
    n_closed = -g * k
    both = wbm.MechanicalSystem(np.diag([m, m]), np.diag([c, c]), np.diag([k, k]))
    basis = wbm.TimeBasis("fourier", 33)
    paired = wbm.solve(both, 0, 1.0, 12.0, [(1, wbm.RigidStop(g)),
                                            (0, wbm.CoulombFriction(friction_coefficient=mu, normal_load=0.0), 0)],
                       basis, basis)
    assert paired["converged"], paired["message"]
    one = wbm.MechanicalSystem([[m]], [[c]], [[k]])
    constant = wbm.solve(one, 0, 1.0, 12.0, [(0, wbm.CoulombFriction(friction_coefficient=mu, normal_load=n_closed))],
                         basis, basis)
    assert constant["converged"], constant["message"]
    x = paired["coefficients"][0]
    assert np.max(np.abs(x - constant["coefficients"][0])) < 1e-9 * np.max(np.abs(x))
    assert np.max(np.abs(paired["contact_force_samples"][0] - n_closed)) < 1e-9 * n_closed
    with pytest.raises(ValueError, match="normal_load = 0.5 N beside a rigid normal stop"):
        wbm.solve(both, 0, 1.0, 12.0, [(1, wbm.RigidStop(g)),
                                       (0, wbm.CoulombFriction(friction_coefficient=mu, normal_load=0.5), 0)],
                  basis, basis)


def test_exact_coulomb_friction_gives_den_hartogs_amplitude_and_its_impulses():
    # The same oscillator with wbm.CoulombFriction (no spring): first order in 1/M, within 5e-3 of
    # Den Hartog at M = 256 and r = 1.5 (measured 4.2e-3; out/friction_coulomb_exact); every
    # impulse slips at ±F0 but at most one per reversal, at the instants returned with them.
    f0 = 0.2
    law = wbm.CoulombFriction(friction_coefficient=f0, normal_load=1.0)
    assert law.rigid
    ratio, s = _den_hartog_ratio(law, f0)
    assert ratio == pytest.approx(1.0, abs=5e-3)
    impulses = s["contact_force_samples"][0]
    assert impulses.shape == (256,) and s["collocation_times"].shape == (256,)
    assert np.max(np.abs(impulses)) == pytest.approx(f0, rel=1e-12)
    assert np.count_nonzero(np.abs(impulses) < f0 * (1.0 - 1e-12)) <= 2
    with pytest.raises(ValueError, match="normal_load"):
        wbm.CoulombFriction(friction_coefficient=0.2, normal_load=-1.0)
