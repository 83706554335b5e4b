"""cli/wbm_plot.py on crafted result folders (issue #40, item 6): a picture of an incomplete
branch says so, a CSV that result.json does not list (an earlier run's) is never drawn, and the
pictures drawn are recorded in result.json so that the next run into the folder removes them.
"""
import importlib.util
import json
import math
from pathlib import Path

import pytest

pytest.importorskip("matplotlib")

SCRIPT = Path(__file__).resolve().parents[2] / "cli" / "wbm_plot.py"


def load_plot_module():
    spec = importlib.util.spec_from_file_location("wbm_plot", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write_csv(path, header, rows):
    path.write_text(",".join(header) + "\n" + "".join(",".join(str(v) for v in r) + "\n" for r in rows))


def plot_folder(tmp_path, result, capture):
    """Writes result.json into tmp_path, runs cli/wbm_plot.py there and returns {picture: capture(figure)}
    for every picture it saves."""
    (tmp_path / "result.json").write_text(json.dumps(result))
    plot = load_plot_module()
    captured = {}
    original = plot.save

    def save(fig, path, written):
        captured[path.name] = capture(fig)
        original(fig, path, written)

    plot.save = save
    assert plot.main(["wbm_plot.py", str(tmp_path), "--quiet"]) == 0
    return captured


def test_an_incomplete_backbone_is_marked_and_unlisted_files_are_not_drawn(tmp_path):
    write_csv(tmp_path / "backbone.csv", ["energy [-]", "frequency [Hz]"], [(0.5, 100.0), (1.5, 104.0), (2.483, 107.0)])
    write_csv(tmp_path / "branch.csv", ["frequency [Hz]", "amplitude_u [m]"], [(1.0, 1.0), (2.0, 2.0)])  # an old run's
    message = "step below minimum at λ = 2.483 (h = 7.74e-08, corrector failed)"
    result = {"converged": False, "files": ["backbone.csv"],
              "scene": {"title": "two masses", "analysis": {"type": "nnm", "energy": [0.5, 10.0]}},
              "diagnostics": {"nnm": {"message": message, "complete": False}}}
    titles = plot_folder(tmp_path, result, lambda fig: fig.axes[0].get_title())
    assert sorted(titles) == ["backbone.png"]  # branch.csv is not this result's
    assert "INCOMPLETE (range 0.5 to 10): " in titles["backbone.png"]
    assert "2.483" in titles["backbone.png"]
    assert not (tmp_path / "response_curve.png").exists()
    assert json.loads((tmp_path / "result.json").read_text())["pictures"] == ["backbone.png"]


def test_a_converged_result_carries_no_mark(tmp_path):
    write_csv(tmp_path / "backbone.csv", ["energy [-]", "frequency [Hz]"], [(0.5, 100.0), (10.0, 120.0)])
    result = {"converged": True, "files": ["backbone.csv"], "scene": {"title": "two masses"}, "diagnostics": {}}
    (tmp_path / "result.json").write_text(json.dumps(result))
    plot = load_plot_module()
    assert plot.incomplete(result) == ""
    assert plot.main(["wbm_plot.py", str(tmp_path), "--quiet"]) == 0
    assert json.loads((tmp_path / "result.json").read_text())["pictures"] == ["backbone.png"]


def test_a_friction_contact_draws_its_hysteresis_loop_with_its_area(tmp_path):
    # An elliptic loop w = A cos θ, f = −F sin θ over one period: ∮ f dw = π A F (closed form);
    # 400 samples and closed trapezoids give it to 4 digits.
    a, f0, n = 2e-4, 0.3, 400
    rows = []
    for q in range(n):
        theta = 2.0 * math.pi * (q + 0.5) / n
        rows.append(((q + 0.5) / n, 0.1 * (q + 0.5) / n, -f0 * math.sin(theta), a * math.cos(theta)))
    write_csv(tmp_path / "contact_force.csv", ["tau [-]", "time [s]", "f_c_x [N]", "w_c_x [m]"], rows)
    result = {"converged": True, "files": ["contact_force.csv"], "scene": {"title": "damper"}, "diagnostics": {}}

    def legend_texts(fig):
        legend = fig.axes[0].get_legend()
        return [t.get_text() for t in legend.get_texts()] if legend else []

    legends = plot_folder(tmp_path, result, legend_texts)
    assert "hysteresis.png" in legends
    (text,) = legends["hysteresis.png"]
    assert text.startswith("x: loop area ")
    assert float(text.split("loop area ")[1].split(" J")[0]) == pytest.approx(math.pi * a * f0, rel=1e-4)


def test_each_kind_of_stability_change_is_marked_once_in_the_legend(tmp_path):
    # bifurcations.csv's status column names the kind; each kind gets one legend entry at its
    # interpolated state, whatever the number of its rows (a kind the plot does not know still
    # draws, with a neutral marker).
    write_csv(tmp_path / "branch.csv", ["frequency [Hz]", "amplitude_x1 [m]", "stable [-]"],
              [(30.0, 1e-3, 1.0), (35.0, 2e-3, 0.0), (40.0, 1.5e-3, 0.0), (45.0, 1e-3, 1.0)])
    header = ["frequency [Hz]", "frequency_before [Hz]", "frequency_after [Hz]", "amplitude_x1 [m]",
              "floquet_multiplier_modulus [-]", "floquet_multiplier_argument [rad]", "stability_lost [-]", "status"]
    write_csv(tmp_path / "bifurcations.csv", header,
              [(32.0, 30.0, 35.0, 1.4e-3, 1.2, 1.4, 1.0, "Neimark-Sacker"),
               (42.0, 40.0, 45.0, 1.2e-3, 1.1, 1.3, 0.0, "Neimark-Sacker"),
               (36.0, 35.0, 40.0, 1.8e-3, 1.05, math.pi, 1.0, "period-doubling")])
    result = {"converged": True, "files": ["branch.csv", "bifurcations.csv"], "scene": {"title": "2 DOF"},
              "diagnostics": {}}
    legends = plot_folder(tmp_path, result, lambda fig: [t.get_text() for t in fig.axes[0].get_legend().get_texts()])
    entries = legends["response_curve.png"]
    assert entries.count("stability change: Neimark-Sacker") == 1
    assert entries.count("stability change: period-doubling") == 1
    assert (tmp_path / "response_curve.png").exists()


def test_points_without_a_stability_verdict_are_drawn_apart(tmp_path):
    # Rigid stops: a point with no exact orbit near it has empty stability cells (branch.csv);
    # it is drawn dotted with its own legend entry, neither stable nor unstable.
    write_csv(tmp_path / "branch.csv", ["frequency [Hz]", "amplitude_x1 [m]", "stable [-]"],
              [(30.0, 1e-3, 1.0), (35.0, 2e-3, ""), (40.0, 1.5e-3, 0.0), (45.0, 1e-3, 1.0)])
    result = {"converged": True, "files": ["branch.csv"], "scene": {"title": "rigid stop"}, "diagnostics": {}}

    def legend_lines_ylabel(fig):
        ax = fig.axes[0]
        return ([t.get_text() for t in ax.get_legend().get_texts()],
                [(line.get_linestyle(), len(line.get_xdata())) for line in ax.get_lines()], ax.get_ylabel())

    drawn = plot_folder(tmp_path, result, legend_lines_ylabel)
    legend, lines, ylabel = drawn["response_curve.png"]
    assert legend.count("no stability verdict") == 1 and "stable" in legend and "unstable" in legend
    assert (":", 2) in lines  # the unavailable point, joined to the next
    # The axis names the amplitude's column (the legend's loop once reused its variable: "unavailable").
    assert ylabel == "amplitude_x1 [m]"


def test_a_branch_in_the_friction_coefficient_is_drawn_against_mu(tmp_path):
    # branch.csv of analysis.parameter = "friction_coefficient" starts with μ; its frequency column
    # is constant. The curve is drawn against μ, its folds at their μ, and the axis says which
    # frequency the branch is at.
    write_csv(tmp_path / "branch.csv", ["friction_coefficient [-]", "frequency [Hz]", "amplitude_x [m]"],
              [(0.0, 10.0, 3e-2), (0.4, 10.0, 2e-2), (0.8, 10.0, 1e-4)])
    write_csv(tmp_path / "folds.csv", ["friction_coefficient [-]", "floquet_crossing [-]", "amplitude_x [m]"],
              [(0.4, 0.0, 2e-2)])
    result = {"converged": True, "files": ["branch.csv", "folds.csv"], "scene": {"title": "damper"},
              "diagnostics": {}}
    drawn = plot_folder(tmp_path, result,
                        lambda fig: (fig.axes[0].get_xlabel(), [list(l.get_xdata()) for l in fig.axes[0].get_lines()]))
    xlabel, lines = drawn["response_curve.png"]
    assert xlabel == "friction coefficient μ [-] (at 10 Hz)"
    assert [0.0, 0.4, 0.8] in lines and [0.4] in lines  # the curve and its fold, in μ
