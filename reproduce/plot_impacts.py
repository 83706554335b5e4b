"""The figures of rigid stops and impacts in reproductions.txt, drawn by plot.py: the JL14 rod against
a rigid stop (Signorini conditions, every Table 2 pair) and the point mass with Newton's impact law
in the Haar weighted residual (issue #38)."""
import json
import math

from plot_common import LABELS, MARKERS, METHODS, column, label_grid_panel, plt, read_csv, save


def rigid_stop(folder):
    """The rigid-stop study: Figs. 6-7 (tip displacement) and 9 (contact force per cell) for each
    case, one panel per combination over the reference, and Figs. 10-11's tip error against M,
    rigid (solid) beside the penalty law (dashed)."""
    meta = json.loads((folder / "meta.json").read_text())
    keys = [k for k in LABELS if k != "bdf"]
    for case in ("case1", "case2"):
        if case not in meta:
            continue
        title = meta[case]["scene"]["title"]
        ref_label = "Moreau-Jean, e = 0" if meta[case].get("reference_periodic") else meta[case]["reference"]["method"]
        for stem, scale, ylabel in (("tip_displacement", 1e3, "tip displacement [mm]"),
                                    ("contact_force", 1e-3, "contact force, mean over a cell [kN]")):
            path = folder / f"{stem}_{case}.csv"
            if not path.exists():
                continue
            header, cols = read_csv(path)
            series = {h.split(" ")[0][2:]: c for h, c in zip(header[1:], cols[1:])}
            fig, axes = plt.subplots(2, 3, figsize=(12.0, 6.4), sharex=True, sharey=True)
            for i, (ax, key) in enumerate(zip(axes.flat, keys)):
                if "reference" in series:
                    draw = ax.plot if stem == "tip_displacement" else (lambda x, y, **k: ax.step(x, y, where="mid", **k))
                    draw(cols[0], [scale * v for v in series["reference"]], color="k", lw=2.5, alpha=0.35,
                         label=ref_label)
                if key in series:
                    draw = ax.plot if stem == "tip_displacement" else (lambda x, y, **k: ax.step(x, y, where="mid", **k))
                    draw(cols[0], [scale * v for v in series[key]], color="C0", lw=0.9,
                         label=f"{LABELS[key]}, M = {meta['figure_dimension']}")
                else:
                    ax.text(0.5, 0.5, f"{LABELS[key]}: not converged", transform=ax.transAxes, ha="center",
                            va="center", fontsize=8)
                if stem == "tip_displacement":
                    ax.axhline(1e3 * meta[case]["gap_m"], color="r", ls=":", lw=1.0, label="rigid stop $g_0$")
                label_grid_panel(ax, i, key, ylabel)
            fig.suptitle(f"Rigid stop: {title}", fontsize=10)
            save(fig, folder, f"{stem}_{case}")
    for metric, ylabel in (("tip_error", "rms relative tip error [-]"), ("energy_norm", "energy norm / reference [-]")):
        fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
        for ax, case in zip(axes, ("case1", "case2")):
            for file, ls, suffix in ((f"sweep_{case}.csv", "-", "rigid"), (f"penalty_{case}.csv", "--", "penalty")):
                path = folder / file
                if not path.exists():
                    continue
                header, cols = read_csv(path)
                values = cols[header.index(f"{metric} [-]")]
                for i, name in enumerate(METHODS[:-1]):
                    pts = [(m, v) for c, m, v in zip(cols[0], cols[1], values) if int(c) == i and math.isfinite(v) and v > 0]
                    if pts:
                        ax.plot(*zip(*pts), marker=MARKERS[i], ls=ls, lw=1.0, color=f"C{i}",
                                alpha=1.0 if suffix == "rigid" else 0.45, label=f"{name} ({suffix})")
            ax.set_xscale("log", base=2)
            if metric == "tip_error":
                ax.set_yscale("log")
            else:
                ax.axhline(1.0, color="k", lw=0.8, ls=":")
            ax.set_xlabel("number of basis functions M [-]")
            ax.set_ylabel(ylabel)
            if case in meta:
                periodic = meta[case].get("reference_periodic")
                ax.set_title(meta[case]["scene"]["title"] + ("" if periodic else "\n(against Fourier:Fourier, largest M)"),
                             fontsize=9)
            ax.legend(fontsize=5, ncol=2)
        fig.suptitle(f"Rigid stop (solid) and penalty law (dashed): {metric.replace('_', ' ')} (Figs. 10-11)")
        fig.tight_layout()
        save(fig, folder, metric)
    path = folder / "frequency_response.csv"
    if path.exists():
        header, cols = read_csv(path)
        penalty = folder.parent / "jl14_fig12" / "branches.csv"
        pen = read_csv(penalty)[1] if penalty.exists() else None
        present = sorted({int(c) for c in cols[0]})
        for stem, wanted in (("frequency_response", [0, 3]), ("frequency_response_all", present)):
            fig, ax = plt.subplots(figsize=(7.0, 4.4))
            marked = set()
            for i in wanted:
                pts = [(f, 1e3 * a) for c, f, a in zip(cols[0], cols[1], cols[2]) if int(c) == i]
                if pts:
                    line, = ax.plot(*zip(*pts), lw=1.2, label=f"{METHODS[i]}, rigid stop")
                    # Stability (stable [-]: 1, 0, or empty = no verdict): unstable and undecided points marked.
                    for value, marker, name in ((0.0, "x", "unstable"), (math.nan, ".", "no stability verdict")):
                        sel = [(f, 1e3 * a) for c, f, a, st in zip(cols[0], cols[1], cols[2], cols[4])
                               if int(c) == i and (st == value or (math.isnan(value) and math.isnan(st)))]
                        if sel:
                            ax.plot(*zip(*sel), marker, ms=4, color=line.get_color() if value == 0.0 else "0.5",
                                    label=name if name not in marked else None)
                            marked.add(name)
                    if pen is not None:
                        pp = [(f, 1e3 * a) for c, f, a in zip(pen[0], pen[1], pen[4]) if int(c) == i]
                        if pp:
                            ax.plot(*zip(*pp), lw=0.8, ls=":", color=line.get_color(),
                                    label=f"{METHODS[i]}, penalty (Fig. 12)")
            ax.axhline(1e3 * meta["frequency_response_gap_m"], color="r", ls=":", lw=1.0, label="gap $g_0$")
            ax.set_xlabel("forcing frequency [Hz]")
            ax.set_ylabel("tip amplitude (max - min)/2 [mm]")
            ax.set_title("Fig. 12 with a rigid stop (continuation; stability of the exact orbit near each point)",
                         fontsize=9)
            ax.legend(fontsize=7)
            save(fig, folder, stem)


def point_mass_impacts(folder):
    """Issue #38, item 3: the Haar weighted residual with Newton's impact law against the exact orbit."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    ax = axes[0]
    e = column(folder, "convergence.csv", "restitution [-]")
    m = column(folder, "convergence.csv", "cells [-]")
    err = column(folder, "convergence.csv", "error [-]")
    mj = column(folder, "convergence.csv", "moreau_jean_error [-]")
    for value, marker in sorted({(v, "o" if v == 0.0 else "s") for v in e}):
        pts = [(x, y) for x, y, r in zip(m, err, e) if r == value and not math.isnan(y)]
        ref = [(x, y) for x, y, r in zip(m, mj, e) if r == value and not math.isnan(y)]
        if pts:
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker + "-", ms=4, label=f"Haar, impact law, e = {value:g}")
        if ref:
            ax.loglog([p[0] for p in ref], [p[1] for p in ref], marker + "--", ms=4, mfc="none",
                      label=f"Moreau–Jean, M steps, e = {value:g}")
    ax.set_xlabel("cells (steps) per period M [-]")
    ax.set_ylabel("rms error against the exact orbit [-]")
    ax.set_title("1-DOF impact oscillator", fontsize=9)
    ax.legend(fontsize=7)
    ax = axes[1]
    for name, style in (("plastic", "-"), ("restitution", "--")):
        path = folder / f"orbit_{name}.csv"
        if not path.exists():
            continue
        tau = column(folder, path.name, "tau [-]")
        exact = column(folder, path.name, "u_exact [m]")
        haar = column(folder, path.name, "u_haar [m]")
        scale = max(abs(x) for x in exact)
        ax.plot(tau, [x / scale for x in exact], "k" + style, lw=1.2, label=f"exact orbit ({name})")
        ax.plot(tau, [x / scale for x in haar], style, lw=0.7, label=f"Haar cells ({name})")
    ax.set_xlabel("τ = t/T [-]")
    ax.set_ylabel("u / max|u_exact| [-]")
    ax.set_title("the orbits at the finest M", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, folder, "point_mass_impacts")
