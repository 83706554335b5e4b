#!/usr/bin/env python3
"""Draws the result folder of `wbm run` as PNG files beside its CSV files (`wbm run` calls it
after a run unless --no-plots; `wbm plot DIR` calls it again).

Usage: wbm_plot.py DIR [--quiet]. Reads DIR/result.json and the CSV files it lists (a CSV of an
earlier run that the result does not list is never drawn); every number on a figure comes from
those files. A result that did not converge is drawn with "INCOMPLETE" and the reason in red in
the title (e.g. a backbone stopped at E = 2.48 of 10). The names of the pictures drawn are added
to result.json under "pictures" (rewritten atomically), so that the next run into DIR removes
them with the rest of the old result. Figures (each only when its CSV is listed):
  time_histories.png   displacement, velocity, contact force and energy over one period
  hysteresis.png       friction force against tangential displacement per friction contact
                       (its w_c_ column of contact_force.csv): the loop whose area is the
                       energy dissipated per cycle
  harmonics.png        amplitudes A_h of harmonics.csv (log scale)
  frequency_response.png  max/min displacement per output DOF of a sweep (restarts marked)
  response_curve.png   amplitude along a continuation branch (against the frequency, or against
                       mu for a branch in the friction coefficient), stable solid, unstable dashed,
                       folds marked (a fold of the dynamics filled, of the truncation open),
                       and bifurcations.csv's changes of stability by kind
  backbone.png         frequency against energy of an nnm backbone, folds marked (and each level's
                       stability with analysis.stability)
  mode_E<E>.png        displacement of the output DOFs over one period at each written level
  basis_functions.png  the functions of a basis-plot
Exit status: 0 drawn (possibly nothing, if the run wrote no curve), 2 DIR holds no result.json,
3 matplotlib cannot be imported (`wbm run` then says plots were skipped).
"""
import csv
import json
import math
import sys
import textwrap
from pathlib import Path

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as error:  # pragma: no cover - depends on the machine
    print(f"wbm plot: matplotlib is not available ({error}); no pictures drawn", file=sys.stderr)
    sys.exit(3)

STYLE = {"figure.figsize": (6.4, 4.0), "axes.grid": True, "grid.alpha": 0.3, "font.size": 10,
         "legend.fontsize": 8, "savefig.dpi": 150}


def read_csv(path):
    """Columns of a result CSV by header; empty cells (missing values) read as NaN; the text
    column "status" is kept as strings."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    table = {}
    for i, name in enumerate(header):
        if name == "status":
            table[name] = [r[i] for r in body]
        else:
            table[name] = [float(r[i]) if r[i] != "" else math.nan for r in body]
    return table


def columns(table, prefix):
    """(label, values) of the columns whose name starts with `prefix`."""
    return [(name, values) for name, values in table.items() if name.startswith(prefix)]


def save(fig, path, written):
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    written.append(path.name)


LISTED = set()  # the result's files (result.json "files"), set by main()
NOTE = ""  # why the result is incomplete ("" when it converged), set by main()


def listed(folder, name):
    """True for a CSV of this result: listed in result.json and present."""
    return name in LISTED and (folder / name).exists()


def incomplete(result):
    """'' for a converged result, else the reason it is incomplete, from result.json."""
    if result.get("converged", True):
        return ""
    d = result.get("diagnostics", {})
    scene = result.get("scene", {}).get("analysis", {})
    for key, what, unit in (("nnm", "energy", ""), ("continuation", "frequency_hz", " Hz")):
        if key in d:
            goal = scene.get("energy" if key == "nnm" else "frequency_hz")
            where = ""
            if isinstance(goal, list) and len(goal) == 2:
                where = f" (range {goal[0]:g} to {goal[1]:g}{unit})"
            return f"INCOMPLETE{where}: " + str(d[key].get("message", "stopped early"))
    return "INCOMPLETE: not converged (result.json: diagnostics)"


def mark(ax, title, note):
    """The title, and a red line saying why the result is incomplete."""
    if note:
        ax.set_title(title + "\n" + "\n".join(textwrap.wrap(note, 80)), fontsize=9, color="C3")
    else:
        ax.set_title(title, fontsize=9)


def time_histories(folder, title, written):
    panels = [(f, p) for f, p in (("displacement.csv", "u_"), ("velocity.csv", "v_"), ("contact_force.csv", "f_c_"),
                                  ("energy.csv", "energy")) if listed(folder, f)]
    if not panels:
        return
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(6.4, 2.0 + 1.6 * len(panels)), squeeze=False)
    for ax, (file, prefix) in zip(axes[:, 0], panels):
        table = read_csv(folder / file)
        for name, values in columns(table, prefix):
            # Rigid stops write one impulse per cell (a few points): mark them.
            ax.plot(table["time [s]"], values, label=name, marker="." if len(values) <= 128 else None)
        ax.set_ylabel(file.removesuffix(".csv").replace("_", " "))
        ax.legend(loc="best")
    axes[-1, 0].set_xlabel("time [s]")
    mark(axes[0, 0], title, NOTE)
    save(fig, folder / "time_histories.png", written)


def hysteresis(folder, title, written):
    """Each friction contact's loop f_c(w_c) over one period, closed (the period's last sample
    joined to its first), with the energy it encloses, the sum of trapezoids of f dw."""
    if not listed(folder, "contact_force.csv"):
        return
    table = read_csv(folder / "contact_force.csv")
    labels = [(name, name[4:].removesuffix(" [m]")) for name, _ in columns(table, "w_c_")]
    loops = [(label, table[f"f_c_{label} [N]"], table[name]) for name, label in labels if f"f_c_{label} [N]" in table]
    if not loops:
        return
    fig, ax = plt.subplots()
    for label, f, w in loops:
        f, w = list(f) + [f[0]], list(w) + [w[0]]
        area = sum(0.5 * (f[i] + f[i + 1]) * (w[i + 1] - w[i]) for i in range(len(w) - 1))
        ax.plot(w, f, label=f"{label}: loop area {area:.4g} J")
    ax.set_xlabel("tangential displacement w_c [m]")
    ax.set_ylabel("friction force f_c [N]")
    ax.legend(loc="best")
    mark(ax, title, NOTE)
    save(fig, folder / "hysteresis.png", written)


def harmonics(folder, title, written):
    if not listed(folder, "harmonics.csv"):
        return
    table = read_csv(folder / "harmonics.csv")
    fig, ax = plt.subplots()
    h = table["h [-]"]
    series = columns(table, "A_")
    width = 0.8 / max(len(series), 1)
    for k, (name, values) in enumerate(series):
        ax.bar([x + k * width for x in h], [abs(v) for v in values], width=width, label=name, log=True)
    ax.set_xlabel("harmonic h [-]")
    ax.set_ylabel("amplitude |A_h| [m]")
    mark(ax, title, NOTE)
    ax.legend()
    save(fig, folder / "harmonics.png", written)


def frequency_response(folder, title, written):
    if not listed(folder, "frequency_response.csv"):
        return
    table = read_csv(folder / "frequency_response.csv")
    f = table["frequency [Hz]"]
    fig, ax = plt.subplots()
    for name, values in columns(table, "max_u_") + columns(table, "min_u_"):
        ax.plot(f, values, marker=".", label=name)
    restarted = [i for i, r in enumerate(table["restarted_from_linear [-]"]) if r == 1.0]
    if restarted:
        first = columns(table, "max_u_")[0][1]
        ax.plot([f[i] for i in restarted], [first[i] for i in restarted], "kx", label="restarted from linear")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("displacement [m]")
    mark(ax, title, NOTE)
    ax.legend()
    save(fig, folder / "frequency_response.png", written)


def response_curve(folder, title, written):
    if not listed(folder, "branch.csv"):
        return
    table = read_csv(folder / "branch.csv")
    # The branch's parameter: the frequency, or mu in a branch in the friction coefficient (its
    # first column; folds.csv and bifurcations.csv then locate their points in mu too).
    x_column = "friction_coefficient [-]" if "friction_coefficient [-]" in table else "frequency [Hz]"
    f = table[x_column]
    amplitudes = columns(table, "amplitude_")  # the forced DOF first, then [output] observe's
    name, amplitude = amplitudes[0]
    stable = table.get("stable [-]")
    fig, ax = plt.subplots()
    if stable is None:
        ax.plot(f, amplitude, "-", color="C0", label=name)
    else:  # one line per run of equal stability, joined at the change
        # An empty cell (NaN) is a point without a verdict (rigid stops: no exact orbit found near it).
        kind = ["unavailable" if math.isnan(v) else ("stable" if v == 1.0 else "unstable") for v in stable]
        style = {"stable": ("-", "C0"), "unstable": ("--", "C0"), "unavailable": (":", "0.5")}
        start = 0
        for i in range(1, len(f) + 1):
            if i == len(f) or kind[i] != kind[start]:
                end = min(i + 1, len(f))
                line, color = style[kind[start]]
                ax.plot(f[start:end], amplitude[start:end], line, color=color)
                start = i
        # (Not `name`: that is the amplitude's column, the axis label and the folds' lookup below.)
        for verdict in ("stable", "unstable", "unavailable"):
            if verdict in kind or verdict != "unavailable":
                ax.plot([], [], style[verdict][0], color=style[verdict][1],
                        label=verdict if verdict != "unavailable" else "no stability verdict")
    for k, (other, values) in enumerate(amplitudes[1:]):
        ax.plot(f, values, "-", color=f"C{k + 1}", linewidth=0.8, label=other)
    if listed(folder, "folds.csv"):
        folds = read_csv(folder / "folds.csv")
        # Each fold at its own state (the amplitude written at the fold): on a multivalued curve
        # the nearest point in frequency may lie on another sheet.
        at_fold = folds[name] if name in folds else None
        for k, (hz, crossing) in enumerate(zip(folds[x_column], folds["floquet_crossing [-]"])):
            if at_fold is not None:
                y = at_fold[k]
            else:  # a result written before folds.csv held the fold's amplitude
                y = amplitude[min(range(len(f)), key=lambda i: abs(f[i] - hz))]
            ax.plot(hz, y, "o", color="C3", fillstyle="full" if crossing == 1.0 else "none")
        ax.plot([], [], "o", color="C3", label="fold")
    if listed(folder, "bifurcations.csv"):
        # Each change of stability at its interpolated state, one marker per kind (the status
        # column): a multiplier through +1, through -1, or a complex pair.
        crossings = read_csv(folder / "bifurcations.csv")
        at = crossings.get(name)
        markers = {"fold": ("s", "C2"), "period-doubling": ("D", "C4"), "Neimark-Sacker": ("*", "C5")}
        shown = set()
        for k, kind in enumerate(crossings["status"]):
            marker, color = markers.get(kind, ("x", "k"))
            hz = crossings[x_column][k]
            y = at[k] if at is not None else amplitude[min(range(len(f)), key=lambda i: abs(f[i] - hz))]
            ax.plot(hz, y, marker, color=color, fillstyle="none", markersize=9,
                    label=None if kind in shown else f"stability change: {kind}")
            shown.add(kind)
    if x_column == "frequency [Hz]":
        ax.set_xlabel("frequency [Hz]")
    else:  # the branch's frequency is one value: say it beside mu
        ax.set_xlabel(f"friction coefficient μ [-] (at {table['frequency [Hz]'][0]:g} Hz)")
    ax.set_ylabel(name if len(amplitudes) == 1 else "amplitude [m]")
    mark(ax, title, NOTE)
    ax.legend()
    save(fig, folder / "response_curve.png", written)


def backbone(folder, title, written):
    if not listed(folder, "backbone.csv"):
        return
    table = read_csv(folder / "backbone.csv")
    e, f = table["energy [-]"], table["frequency [Hz]"]
    fig, ax = plt.subplots()
    ax.plot(e, f, ".-", label="nonlinear mode")
    if "stable [-]" in table:  # analysis.stability: each level's verdict (empty: no exact orbit near it)
        for value, style, name in ((1.0, "o", "stable"), (0.0, "x", "unstable")):
            pts = [(x, y) for x, y, v in zip(e, f, table["stable [-]"]) if v == value]
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=4, mfc="none", label=name)
    if listed(folder, "folds.csv"):
        folds = read_csv(folder / "folds.csv")
        for k, energy in enumerate(folds["energy [-]"]):
            if "frequency [Hz]" in folds:  # the fold's own frequency (multivalued in E)
                y = folds["frequency [Hz]"][k]
            else:  # a result written before folds.csv held it
                y = f[min(range(len(e)), key=lambda i: abs(e[i] - energy))]
            ax.plot(energy, y, "o", color="C3")
    ax.axvline(1.0, color="0.5", linewidth=0.8, label="contact onset (energy 1)")
    ax.set_xscale("log")
    ax.set_xlabel("energy [-] (1 at contact onset)")
    ax.set_ylabel("frequency [Hz]")
    mark(ax, title, NOTE)
    ax.legend()
    save(fig, folder / "backbone.png", written)


def modes(folder, title, written):
    for path in sorted(folder.glob("mode_E*.csv")):
        if path.stem.endswith("_contact") or not listed(folder, path.name):
            continue
        table = read_csv(path)
        fig, ax = plt.subplots()
        for name, values in columns(table, "u_"):
            ax.plot(table["tau [-]"], values, label=name)
        ax.set_xlabel("tau [-]")
        ax.set_ylabel("displacement [m]")
        ax.set_title(f"{title}: {path.stem}", fontsize=9)
        if len(columns(table, "u_")) <= 12:
            ax.legend(loc="best")
        save(fig, folder / f"{path.stem}.png", written)


def basis_functions(folder, title, written):
    if not listed(folder, "basis_functions.csv"):
        return
    table = read_csv(folder / "basis_functions.csv")
    fig, ax = plt.subplots()
    for name, values in list(table.items())[1:]:
        ax.plot(table["tau [-]"], values, label=name)
    ax.set_xlabel("tau [-]")
    ax.set_title(title, fontsize=9)
    if len(table) <= 13:
        ax.legend(loc="best")
    save(fig, folder / "basis_functions.png", written)


def main(argv):
    args = [a for a in argv[1:] if a != "--quiet"]
    quiet = len(args) != len(argv) - 1
    if len(args) != 1:
        print("usage: wbm_plot.py DIR [--quiet]", file=sys.stderr)
        return 2
    folder = Path(args[0])
    if not (folder / "result.json").exists():
        print(f"wbm plot: {folder}: no result.json (not a folder written by `wbm run`)", file=sys.stderr)
        return 2
    result = json.loads((folder / "result.json").read_text())
    LISTED.update(result.get("files", []))
    global NOTE
    NOTE = incomplete(result)
    scene = result.get("scene", {})
    title = "\n".join(textwrap.wrap(scene.get("title") or Path(result.get("scene_file", str(folder))).stem, 70))
    plt.rcParams.update(STYLE)
    written = []
    for draw in (time_histories, hysteresis, harmonics, frequency_response, response_curve, backbone, modes, basis_functions):
        draw(folder, title, written)
    result["pictures"] = written
    staged = folder / ".result.json.pictures"
    staged.write_text(json.dumps(result, indent=2) + "\n")
    staged.replace(folder / "result.json")  # atomic: result.json stays the marker of a complete set
    if not quiet:
        print(f"wbm plot: drew {len(written)} picture(s) in {folder}" + (": " + ", ".join(written) if written else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
