#!/usr/bin/env python3
"""Renders every figure of out/ that reproductions.txt names to PNG and PDF beside its CSV.

Usage: plot.py OUT_DIR. Each figure id maps (reproductions.txt) to a short function here that
reads the CSV, labels the axes from its header (units in brackets) and applies the shared style.
Figures whose folder is missing are skipped with a note (a failed run writes no folder).

One plotting module: the CSV reader and the style are those of `wbm run`'s pictures
(cli/wbm_plot.py, loaded from the source tree; plot_common.py); this file holds the papers' figures
and the blade's, plot_friction.py the friction figures of issue #36, plot_impacts.py those of rigid
stops and impacts (JL14 with a rigid stop, point masses with Newton's impact law).
"""
import json
import math
import multiprocessing
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # plot_common, plot_friction, plot_impacts beside this file
from plot_common import (LABELS, MARKERS, METHODS, STYLE, _load, column, label_grid_panel, plt, read_csv,  # noqa: E402
                         read_status, save, wbm_plot)
from plot_friction import (friction_coulomb_exact, friction_den_hartog, friction_normal_load,  # noqa: E402,F401
                           friction_oval_casing, friction_rigid_normal)
from plot_impacts import point_mass_impacts, rigid_stop  # noqa: E402,F401


def history(folder):
    """Figs. 6-9 as the paper draws them: one panel per combination of Table 2, (a)-(f) in the
    paper's order, each over the BDF reference; a combination missing from the CSV (not
    converged) keeps its panel, with its status from meta.json."""
    meta = json.loads((folder / "meta.json").read_text())
    quantity = meta["quantity"]
    stem = {"displacement": "tip_displacement", "velocity": "tip_velocity", "force": "contact_force"}[quantity]
    header, cols = read_csv(folder / f"{stem}.csv")
    scale = 1e3 if quantity == "displacement" else 1.0
    series = {name.split(" ")[0].split("_", 2)[-1]: col for name, col in zip(header[1:], cols[1:])}
    statuses = {r.get("combination"): r.get("status") for r in meta.get("combinations", []) if isinstance(r, dict)}
    keys = [k for k in LABELS if k != "bdf"]
    fig, axes = plt.subplots(2, 3, figsize=(12.0, 6.4), sharex=True, sharey=True)
    ylabel = {"displacement": "tip displacement [mm]", "velocity": "tip velocity [m/s]",
              "force": "contact force / F [-]"}[quantity]
    for i, (ax, key) in enumerate(zip(axes.flat, keys)):
        if "bdf" in series:
            ax.plot(cols[0], [scale * v for v in series["bdf"]], color="k", lw=2.5, alpha=0.35, label=LABELS["bdf"])
        if key in series:
            ax.plot(cols[0], [scale * v for v in series[key]], color="C0", lw=0.9,
                    label=f"{LABELS[key]}, M = {meta['figure_dimension']}")
        else:
            ax.text(0.5, 0.5, f"{LABELS[key]}: {statuses.get(LABELS[key], 'not in the CSV')}",
                    transform=ax.transAxes, ha="center", va="center", fontsize=8)
        if quantity == "displacement":
            ax.axhline(1e3 * meta["gap_m"], color="r", ls=":", lw=1.0, label="gap $g_0$")
        label_grid_panel(ax, i, key, ylabel)
    fig.suptitle(f"{meta['figure']}: {meta['scene']['title']}", fontsize=10)
    save(fig, folder, stem)


def sweep(folder):
    """Figs. 10-11: a metric against M for both cases, one curve per combination."""
    meta = json.loads((folder / "meta.json").read_text())
    metric = meta["metric"]
    column_name = {"tip_error": "tip_error [-]", "energy_norm": "energy_norm [-]"}[metric]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    for ax, case, tag in zip(axes, ("case1", "case2"), ("(a)", "(b)")):
        path = folder / f"sweep_{case}.csv"
        if not path.exists():
            continue
        header, cols = read_csv(path)
        values = cols[header.index(column_name)]
        for i, name in enumerate(METHODS[:-1]):
            # empty cells (read as NaN) are solves that did not converge: not drawn
            pts = [(m, v) for c, m, v in zip(cols[0], cols[1], values) if int(c) == i and math.isfinite(v)]
            if pts:
                ax.plot(*zip(*pts), marker=MARKERS[i], lw=1.0, label=name)
        ax.set_xscale("log", base=2)
        if metric == "tip_error":
            ax.set_yscale("log")
        else:
            ax.axhline(1.0, color="k", lw=0.8, ls=":")
        ax.set_xlabel("number of basis functions M [-]")
        ax.set_ylabel("rms relative tip error [-]" if metric == "tip_error" else "energy norm / BDF [-]")
        ax.set_title(f"{tag} {meta[case]['scene']['title']}", fontsize=9)
        ax.legend()
    fig.suptitle(meta["figure"])
    fig.tight_layout()
    save(fig, folder, metric)


def speed_accuracy(folder):
    """Error against wall time per method, Pareto front as a step line."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.4))
    for ax, case in zip(axes, ("case1", "case2")):
        path = folder / f"speed_accuracy_{case}.csv"
        if not path.exists():
            ax.set_visible(False)
            continue
        header, cols = read_csv(path)
        method, err, time, pareto = (cols[header.index(h)] for h in
                                     ("method [-]", "tip_error [-]", "time [s]", "pareto [-]"))
        rows = list(zip(method, err, time, pareto))
        for i, name in enumerate(METHODS):
            # empty cells (NaN) are runs that did not converge: not drawn
            pts = [(t, e) for m, e, t, _ in rows if int(m) == i and math.isfinite(e)]
            if pts:
                ax.plot(*zip(*sorted(pts)), marker=MARKERS[i], lw=0.8, label=name)
        front = sorted((t, e) for _, e, t, p in rows if p == 1.0)
        if front:
            ax.step(*zip(*front), where="post", color="k", lw=1.5, alpha=0.4, label="Pareto front")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time of a full solve [s]")
        ax.set_ylabel("rms relative tip error [-]")
        ax.set_title(json.loads((folder / "meta.json").read_text())[case]["scene"]["title"], fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, folder, "speed_accuracy")


def basis_functions(folder):
    """Figs. 2-5: one panel per column of basis.csv (six functions or six levels)."""
    header, cols = read_csv(folder / "basis.csv")
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(2, 3, figsize=(9.0, 5.0), sharex=True)
    for ax, name, col in zip(axes.flat, header[1:], cols[1:]):
        ax.plot(cols[0], col, lw=1.0)
        ax.ticklabel_format(axis="y", useOffset=False)
        if max(col) - min(col) < 1e-9:  # J = 0: the constant 1
            ax.set_ylim(min(col) - 0.5, max(col) + 0.5)
        ax.set_title(name.split(" [")[0].replace("phi_J", "J = ").replace("_0", ", k = 0"), fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel(header[0])
    title = meta.get("family", meta.get("basis", ""))
    norm = ", normalized by ∫φ = 1" if meta.get("normalization") == "unit integral" else ""
    fig.suptitle(f"{meta['figure']}: {title} basis functions{norm}")
    fig.tight_layout()
    save(fig, folder, "basis")


def frequency_response(folder):
    """Fig. 12: tip amplitude against frequency, unstable parts dashed, linear and BDF overlaid."""
    _, b = read_csv(folder / "branches.csv")
    _, lin = read_csv(folder / "linear.csv")
    bdf = read_csv(folder / "bdf.csv")[1] if (folder / "bdf.csv").exists() else None
    meta = json.loads((folder / "meta.json").read_text())
    gap = meta["gap_m"]
    present = sorted({int(c) for c in b[0]})
    for stem, wanted in (("frequency_response", [0, 3]), ("frequency_response_all", present)):
        fig, ax = plt.subplots(figsize=(7.0, 4.4))
        ax.plot(lin[0], [1e3 * a for a in lin[1]], color="0.6", lw=1.0, label="linear (no contact)")
        for i in wanted:
            pts = [(f, 1e3 * a, s) for c, f, a, s in zip(b[0], b[1], b[4], b[5]) if int(c) == i]
            if not pts:
                continue
            color = None
            # Consecutive points of equal stability form one segment; unstable ones dashed.
            start = 0
            for k in range(1, len(pts) + 1):
                if k == len(pts) or pts[k][2] != pts[start][2]:
                    seg = pts[max(0, start - 1):k]
                    line, = ax.plot([p[0] for p in seg], [p[1] for p in seg], color=color,
                                    ls="-" if pts[start][2] == 1.0 else "--", lw=1.2,
                                    label=METHODS[i] if color is None else None)
                    color = line.get_color()
                    start = k
        if bdf:
            ax.plot(bdf[0], [1e3 * a for a in bdf[3]], "kx", ms=7, label="time stepping (BDF), from rest")
        ax.axhline(1e3 * gap, color="k", lw=0.6, ls=":", label="gap")
        # A branch that ran off (stopped at the state bound) would flatten the figure: the axis
        # stops at 1.2 x the linear peak, and the caption says which branches leave it.
        top = 1.2e3 * max(lin[1])
        off = [METHODS[i] for i in wanted if any(int(c) == i and 1e3 * a > top for c, a in zip(b[0], b[4]))]
        ax.set_ylim(0.0, top)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("tip amplitude (max - min)/2 [mm]")
        note = f"; off scale: {', '.join(off)} (see REPORT)" if off else ""
        ax.set_title(f"{meta['figure']}: M = {meta['dimension']}, unstable dashed{note}", fontsize=9)
        ax.legend()
        fig.tight_layout()
        save(fig, folder, stem)


def frequency_energy(folder):
    """LL11 Fig. 3: orbit frequency (solid) and Rayleigh quotient (dashed) against normalized energy."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    e = column(folder, "backbone.csv", "energy [-]")
    f = column(folder, "backbone.csv", "frequency [Hz]")
    fr = column(folder, "backbone.csv", "rayleigh_frequency [Hz]")
    e8 = column(folder, "n8_backbone.csv", "energy [-]")
    f8 = column(folder, "n8_backbone.csv", "frequency [Hz]")
    for ax, emax in zip(axes, (max(e), 2.5)):
        ax.plot(e, f, "C0-", lw=1.0, label=f"orbit frequency, N = {meta['harmonics']}")
        ax.plot(e, fr, "C0--", lw=0.8, label=f"Rayleigh quotient √r (paper's ω), N = {meta['harmonics']}")
        ax.plot(e8, f8, "C1-", lw=0.7, alpha=0.7, label="orbit frequency, N = 8")
        if (folder / "n16_backbone.csv").exists():
            ax.plot(column(folder, "n16_backbone.csv", "energy [-]"), column(folder, "n16_backbone.csv", "frequency [Hz]"),
                    "C2-", lw=0.7, alpha=0.7, label="orbit frequency, N = 16, m = 128")
        for stem, marker, name in (("alg1_", "o", "LL11 Alg. 1 (simultaneous)"), ("alg2_", "x", "LL11 Alg. 2 (sequential)")):
            if (folder / f"{stem}backbone.csv").exists():
                ax.plot(column(folder, f"{stem}backbone.csv", "energy [-]"),
                        column(folder, f"{stem}backbone.csv", "frequency [Hz]"), marker, color="k", ms=4,
                        mfc="none", label=name + ", N = 8")
        ax.axvline(1.0, color="0.5", lw=0.6, ls=":")
        ax.set_xlim(min(e), emax)
        ax.set_xlabel("normalized modal energy E [-] (1: contact onset)")
        ax.set_ylabel("frequency [Hz]")
    axes[0].set_title(f"{meta['figure']}: first nonlinear mode, linear {meta['linear_frequency_hz']:.1f} Hz", fontsize=9)
    axes[1].set_title("zoom on E ≤ 2.5 (turning points at internal resonances)", fontsize=9)
    axes[1].set_ylim(meta["linear_frequency_hz"] - 0.5, max(x for x, y in zip(f, e) if y <= 2.5) + 0.5)
    axes[0].legend(loc="lower right")
    fig.tight_layout()
    save(fig, folder, "frequency_energy")


def mode_fields(folder, energy):
    header, cols = read_csv(folder / f"mode_E{energy:g}.csv")
    u = [cols[i] for i, h in enumerate(header) if h.startswith("u_node")]
    v = [cols[i] for i, h in enumerate(header) if h.startswith("v_node")]
    return cols[0], u, v


def phase_space(folder):
    """LL11 Fig. 4: last and first node displacement against middle node displacement and velocity."""
    meta = json.loads((folder / "meta.json").read_text())
    fig = plt.figure(figsize=(10.0, 4.6))
    names = meta["nodes"]
    for k, (node, tag) in enumerate(((names[2], "(a) last node"), (names[0], "(b) first node"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for level in meta["levels"]:
            header, cols = read_csv(folder / f"mode_E{level['energy']:g}.csv")
            get = lambda name: cols[header.index(name)]  # noqa: E731
            um, vm, uz = get(f"u_{names[1]} [m]"), get(f"v_{names[1]} [m/s]"), get(f"u_{node} [m]")
            close = lambda x: x + x[:1]  # noqa: E731
            ax.plot(close([1e3 * x for x in um]), close(vm), close([1e3 * x for x in uz]), lw=1.0,
                    label=f"E = {level['energy']:g} ({level['frequency_hz']:.2f} Hz)")
        ax.view_init(elev=20, azim=-35)
        ax.set_xlabel(f"u {names[1]} [mm]", fontsize=8)
        ax.set_ylabel(f"du/dt {names[1]} [m/s]", fontsize=8)
        ax.set_zlabel(f"u {node} [mm]", fontsize=8)
        ax.set_title(f"{meta['figure']} {tag}", fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, folder, "phase_space")


def space_time(folder):
    """LL11 Fig. 5: displacement and velocity of every node over one period, E = 0.7 and 1.8."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(2, 2, figsize=(9.0, 6.4))
    for row, level in enumerate(meta["levels"][:2]):
        tau, u, v = mode_fields(folder, level["energy"])
        for col, (field, name, unit) in enumerate(((u, "displacement", 1e3), (v, "velocity", 1.0))):
            ax = axes[row][col]
            data = [[unit * x for x in r] for r in field]
            im = ax.imshow(data, aspect="auto", origin="lower", cmap="RdBu_r",
                           extent=(0.0, 1.0, 0.5, len(field) + 0.5))
            fig.colorbar(im, ax=ax, label="mm" if col == 0 else "m/s")
            ax.set_xlabel("normalized time t/T [-]")
            ax.set_ylabel("node")
            ax.set_title(f"({'abcd'[2 * row + col]}) {name}, E = {level['energy']:g}", fontsize=9)
            ax.grid(False)
    fig.suptitle(f"{meta['figure']}: space–time maps of the first nonlinear mode", fontsize=10)
    fig.tight_layout()
    save(fig, folder, "space_time")


def penalty_limit(folder):
    """Issue #7: penalty backbones approach the exact-contact one as the stiffness grows."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    ax = axes[0]
    ax.plot(column(folder, "exact_backbone.csv", "energy [-]"), column(folder, "exact_backbone.csv", "frequency [Hz]"),
            "k-", lw=1.6, label="exact (Signorini)")
    for p in meta["penalty"]:
        stem = f"k{p['stiffness_N_per_m']:.0e}_backbone.csv".replace("e+", "e+")
        if (folder / stem).exists():
            ax.plot(column(folder, stem, "energy [-]"), column(folder, stem, "frequency [Hz]"), lw=0.9,
                    label=f"penalty k = {p['stiffness_N_per_m']:.0e} N/m")
    ax.set_xlabel("normalized modal energy E [-]")
    ax.set_ylabel("orbit frequency [Hz]")
    ax.set_title("backbones", fontsize=9)
    ax.legend()
    ax = axes[1]
    ks = [p["stiffness_N_per_m"] for p in meta["penalty"]]
    ax.loglog(ks, [p["max_frequency_difference_hz"] for p in meta["penalty"]], "o-", label="max |f_k − f_exact|")
    ax.loglog(ks, [p["max_penetration_gaps"] for p in meta["penalty"]], "s--", label="max penetration [g0]")
    ax.set_xlabel("penalty stiffness k [N/m]")
    ax.set_title(f"largest difference over E ≤ 1.1: order "
                 f"{meta['observed_order_in_1_over_k']:.2f} in 1/k", fontsize=9)
    ax.legend()
    fig.tight_layout()
    save(fig, folder, "penalty_limit")


def backbone_stability(folder):
    """Issue #38: the LL11 rod's backbone marked stable / unstable by its exact orbits' multipliers."""
    meta = json.loads((folder / "meta.json").read_text())
    e = column(folder, "stability.csv", "energy [-]")
    f = column(folder, "stability.csv", "frequency [Hz]")
    mu = column(folder, "stability.csv", "max_multiplier [-]")
    stable = column(folder, "stability.csv", "stable [-]")
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    ax = axes[0]
    ax.plot(e, f, "-", color="0.6", lw=0.8, label=f"KKT backbone, N = {meta['harmonics']}")
    for value, style, name in ((1.0, "o", "stable"), (0.0, "x", "unstable")):
        pts = [(x, y) for x, y, s in zip(e, f, stable) if s == value]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=3, mfc="none", label=name)
    missing = [(x, y) for x, y, s in zip(e, f, stable) if math.isnan(s)]
    if missing:
        ax.plot([p[0] for p in missing], [p[1] for p in missing], ".", color="0.3", ms=2, label="no verdict")
    ax.axvline(1.0, color="0.5", lw=0.6, ls=":")
    ax.set_xlabel("normalized modal energy E [-] (1: contact onset)")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title("first nonlinear mode, exact orbits with elastic impacts", fontsize=9)
    ax.legend(loc="lower right")
    ax = axes[1]
    ax.semilogy(e, mu, "k.", ms=2)
    ax.axhline(1.0, color="0.5", lw=0.6, ls=":")
    ax.set_xlabel("normalized modal energy E [-]")
    ax.set_ylabel("largest nontrivial |μ| [-]")
    ax.set_title(f"{meta['stable']} stable, {meta['unstable']} unstable, {meta['unavailable']} without verdict",
                 fontsize=9)
    fig.tight_layout()
    save(fig, folder, "backbone_stability")


def wavelet_modes(folder):
    """Issue #38, item 5: the frequency error of the LL11 rod's nonlinear mode per basis against exact orbits."""
    meta = json.loads((folder / "meta.json").read_text())
    energies = meta["energies"]
    fig, axes = plt.subplots(1, len(energies), figsize=(5.0 * len(energies), 4.0), squeeze=False)
    for ax, energy in zip(axes[0], energies):
        for key, label, marker in (("fourier", "Fourier", "o"), ("bspline", "B-spline", "s"), ("db6", "DB6", "^"),
                                   ("haar", "Haar (delta-pair velocity)", "v")):
            path = folder / f"{key}.csv"
            if not path.exists():
                continue
            unknowns = column(folder, f"{key}.csv", "unknowns [-]")
            error = column(folder, f"{key}.csv", f"error_E{energy:g} [-]")
            pts = [(u, abs(e)) for u, e in zip(unknowns, error) if not math.isnan(e) and e != 0.0]
            if pts:
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker + "-", ms=4, mfc="none", label=label)
        ax.axhline(meta["target"], color="0.5", lw=0.6, ls=":", label=f"target {meta['target']:g}")
        ax.set_xlabel("unknowns of the KKT system [-]")
        ax.set_ylabel("|f / f_exact − 1| [-]")
        ax.set_title(f"first nonlinear mode at E = {energy:g}", fontsize=9)
        ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    save(fig, folder, "wavelet_modes")


def free_vibration(folder):
    """Issue #7: deviation of a free time simulation from the computed modes, period by period."""
    meta = json.loads((folder / "meta.json").read_text())
    header, cols = read_csv(folder / "deviation.csv")
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for k, level in enumerate(meta["levels"]):
        rows = [i for i, e in enumerate(cols[0]) if e == level["energy"]]
        ax.semilogy([cols[1][i] for i in rows], [cols[2][i] for i in rows], "o-", color=f"C{k}",
                    label=f"E = {level['energy']:g}, T from the orbit frequency")
        ax.semilogy([cols[1][i] for i in rows], [cols[3][i] for i in rows], "x--", color=f"C{k}",
                    label=f"E = {level['energy']:g}, T from the Rayleigh quotient")
    ax.set_xlabel("period [-]")
    ax.set_ylabel("max |u(t) − u_mode(t)| / max |u_mode| [-]")
    ax.set_title(f"free vibration from the modes (stop: spring {meta['penalty_N_per_m']:.0e} N/m)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, folder, "free_vibration")


def blade(folder):
    """LL11 Figs. 6-8 on our blade: the mesh with the 24 contact nodes (Fig. 6), f/f1 against
    normalized energy (Fig. 7; levels where the first mode at the fundamental holds less than half
    of the energy marked), and the deformed blade at t = 0 and T/2 for the levels shown,
    displacements in units of the gap (Fig. 8), with the tip's radial displacement along the chord."""
    meta = json.loads((folder / "meta.json").read_text())
    header, nodes = read_csv(folder / "mesh_nodes.csv")
    ids, x, y, z = nodes
    ch, cn = read_csv(folder / "contact_nodes.csv")
    cx, cy, cz = (cn[ch.index(k)] for k in ("x [m]", "y [m]", "z [m]"))
    fig = plt.figure(figsize=(10.0, 4.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.scatter([1e3 * v for v in x], [1e3 * v for v in y], [1e3 * v for v in z], s=0.3, c="0.6", alpha=0.4)
    ax.scatter([1e3 * v for v in cx], [1e3 * v for v in cy], [1e3 * v for v in cz], s=12, c="r")
    ax.set_xlabel("x (engine axis) [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z (radial) [mm]")
    ax.set_box_aspect((1, 1, 1.6))
    ax.set_title(f"LL11 Fig. 6: {meta['nodes']} nodes, {meta['c3d10_elements']} C3D10, {meta['dofs']} DOFs", fontsize=9)
    ax2 = fig.add_subplot(1, 2, 2)
    top = max(z)
    tipx = [1e3 * a for a, c in zip(x, z) if abs(c - top) < 1e-9]
    tipy = [1e3 * b for b, c in zip(y, z) if abs(c - top) < 1e-9]
    ax2.plot(tipx, tipy, ".", color="0.6", ms=2, label="tip-face nodes")
    ax2.plot([1e3 * v for v in cx], [1e3 * v for v in cy], "o", color="r", ms=4, label="contact interface (24 nodes)")
    ax2.annotate("leading edge (#1)", (1e3 * cx[0], 1e3 * cy[0]), fontsize=8)
    ax2.annotate("trailing edge (#24)", (1e3 * cx[-1], 1e3 * cy[-1]), fontsize=8)
    ax2.set_aspect("equal")
    ax2.set_xlabel("x [mm]")
    ax2.set_ylabel("y [mm]")
    ax2.set_title("tip face seen from the casing", fontsize=9)
    ax2.legend(loc="lower right")
    fig.tight_layout()
    save(fig, folder, "mesh")

    fig, ax = plt.subplots()
    branch = column(folder, "backbone.csv", "branch [-]")
    e_all = column(folder, "backbone.csv", "energy [-]")
    r_all = column(folder, "backbone.csv", "frequency_over_f1 [-]")
    share_all = column(folder, "backbone.csv", "first_mode_share [-]")
    pick = lambda values, which: [v for v, b in zip(values, branch) if b == which]
    e, r, share = pick(e_all, 0), pick(r_all, 0), pick(share_all, 0)
    ax.plot(e, r, "C0-", lw=1.2, label=f"branch 0, from the linear mode, N = {meta['harmonics']}, m = {meta['samples']}")
    first = meta.get("first_mode_branch")
    if first:
        ax.plot(pick(e_all, 1), pick(r_all, 1), "C2-", lw=1.2,
                label=f"branch 1, first bending mode (start: N = 3 level at E = {first['start_energy']:g}, penalty homotopy)")
    low = [(a, b) for a, b, s in zip(e_all, r_all, share_all) if s < 0.5]
    if low:
        end = meta["end_component"]
        ax.plot([a for a, _ in low], [b for _, b in low], ".", color="0.45", ms=2.5,
                label=f"mode 1 at h = 1 holds < 1/2 of the energy (branch 0 ends with mode {end['mode']} "
                      f"at h = {end['harmonic']}: {end['share']:.2f})")
    for level in meta["levels"]:
        ax.plot(level["energy"], level["frequency_over_f1"], "ko", mfc="none", ms=5)
    ax.axvline(1.0, color="0.5", lw=0.6, ls=":")
    ax.set_xlabel("normalized modal energy E [-] (1: contact onset)")
    ax.set_ylabel("frequency / first linear frequency [-]")
    ax.set_title(f"LL11 Fig. 7 (our blade): f1 = {meta['linear_frequency_hz']:.1f} Hz", fontsize=9)
    ax.legend(loc="center right", fontsize=7)
    save(fig, folder, "frequency_energy")

    levels = [lv["energy"] for lv in meta["levels"]]
    fig = plt.figure(figsize=(4.0 * len(levels), 8.0))
    for i, energy in enumerate(levels):
        dh, d = read_csv(folder / f"deformed_E{energy:g}.csv")
        ax = fig.add_subplot(2, len(levels), i + 1, projection="3d")
        umax = max(max(abs(v) for v in d[k]) for k in range(1, 7)) or 1.0
        scale = 0.1 * (max(z) - min(z)) / umax  # the largest displacement drawn at 10 % of the span
        for offset, colour, name in ((1, "C0", "t = 0"), (4, "C3", "t = T/2")):
            ax.scatter([1e3 * (a + scale * u) for a, u in zip(x, d[offset])],
                       [1e3 * (b + scale * u) for b, u in zip(y, d[offset + 1])],
                       [1e3 * (c + scale * u) for c, u in zip(z, d[offset + 2])], s=0.2, c=colour, alpha=0.3, label=name)
        ax.set_box_aspect((1, 1, 1.6))
        ax.set_title(f"E = {energy:g} (branch {meta['levels'][i].get('branch', 0)}): "
                     f"f/f1 = {meta['levels'][i]['frequency_over_f1']:.4f}\n"
                     f"max |u| = {umax:.1f} g0 drawn at 10 % of the span", fontsize=8)
        ax.legend(loc="upper left", markerscale=10)
        th, t = read_csv(folder / f"tip_E{energy:g}.csv")
        ax2 = fig.add_subplot(2, len(levels), len(levels) + i + 1)
        ax2.plot(t[0], t[1], "C0-o", ms=3, label="t = 0")
        ax2.plot(t[0], t[2], "C3-s", ms=3, label="t = T/2")
        ax2.plot(t[0], t[3], "k:", lw=0.8, label="max over the period")
        ax2.axhline(1.0, color="r", lw=0.8, label="casing (gap)")
        ax2.set_xlabel("tip chord fraction (0: leading edge) [-]")
        ax2.set_ylabel("radial displacement / gap [-]")
        ax2.legend(fontsize=7)
    fig.suptitle("LL11 Fig. 8 (our blade): deformed shapes at three energies, displacements in units of the gap",
                 fontsize=10)
    fig.tight_layout()
    save(fig, folder, "deformed")


def blade_forced(folder):
    """Beyond LL11: the reduced blade's forced response near its first bending resonance (penalty
    stops, Fourier:Fourier and B-spline:B-spline; rigid stops, Fourier:Fourier), their unstable
    points and changes of stability by kind, the linear response, and two backbone branches of
    the same stops overlaid (from the linear mode; through the resonance peak), their levels marked
    where the first mode holds less than half of the energy; amplitudes in gaps."""
    meta = json.loads((folder / "meta.json").read_text())
    bh, b = read_csv(folder / "branches.csv")
    curve, ratio, amp, stable = (b[bh.index(k)] for k in ("curve [-]", "frequency_over_f1 [-]", "amplitude [gap]",
                                                         "stable [-]"))
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    ax.plot(column(folder, "linear.csv", "frequency_over_f1 [-]"), column(folder, "linear.csv", "amplitude [gap]"),
            color="0.6", lw=0.8, ls=":", label="linear (no casing)")
    styles = ["C0-", "C2--", "C1:", "C3-"]
    marked = False
    for i, c in enumerate(meta["curves"]):
        pts = [(r, a, s) for r, a, s, j in zip(ratio, amp, stable, curve) if j == i]
        line, = ax.plot([p[0] for p in pts], [p[1] for p in pts], styles[i % len(styles)], lw=1.2,
                        label=f"{c['curve']} ({c['points']} points)")
        # Unstable points (stable [-] = 0; empty = not computed) marked on the curve.
        bad = [(r, a) for r, a, s in pts if s == 0.0]
        if bad:
            ax.plot(*zip(*bad), "x", ms=3, color=line.get_color(), label="unstable points" if not marked else None)
            marked = True
    # Each change of stability, marked by its kind (bifurcations.csv: fold, period doubling, Neimark-Sacker).
    if (folder / "bifurcations.csv").exists():
        ch, cols = read_csv(folder / "bifurcations.csv")
        kinds = read_status(folder / "bifurcations.csv")
        markers = {"fold": ("o", "fold (multiplier through +1)"), "period-doubling": ("s", "period doubling (-1)"),
                   "Neimark-Sacker": ("D", "Neimark-Sacker (complex pair)")}
        for kind, (marker, name) in markers.items():
            sel = [(r, a) for r, a, k in zip(cols[ch.index("frequency_over_f1 [-]")], cols[ch.index("amplitude [gap]")],
                                             kinds) if k == kind]
            if sel:
                ax.plot(*zip(*sel), marker, ms=6, mfc="none", color="k", label=f"stability change: {name}")
    kh, k = read_csv(folder / "backbone.csv")
    branch, kr, ka, share = (k[kh.index(c)] for c in ("branch [-]", "frequency_over_f1 [-]", "amplitude [gap]",
                                                      "first_mode_share [-]"))
    labels = [f"backbone from the linear mode ({meta['backbone_levels']} levels)",
              f"backbone through the peak ({meta['peak_branch_levels']} levels)"]
    for i, (style, label) in enumerate(zip(["k-.", "m--"], labels)):
        ax.plot([r for r, j in zip(kr, branch) if j == i], [a for a, j in zip(ka, branch) if j == i], style, lw=1.0,
                label=label)
    low = [(r, a) for r, a, s in zip(kr, ka, share) if s < 0.5]
    if low:
        ax.plot([r for r, _ in low], [a for _, a in low], ".", color="0.45", ms=2.5,
                label="backbone levels where mode 1 at the fundamental holds < 1/2 of the energy")
    top = max(amp) * 1.15
    ax.set_ylim(0.0, top)
    ax.set_xlim(min(ratio), max(ratio))
    ax.set_xlabel(f"forcing frequency / f1 [-] (f1 = {meta['linear_frequency_hz']:.1f} Hz)")
    ax.set_ylabel(f"circumferential amplitude of tip node #{meta['onset_node_index']} / gap [-]")
    ax.set_title(f"Reduced blade against the casing: zeta = {meta['zeta']:g}, gap {1e3 * meta['gap_m']:g} mm, "
                 f"{meta['reduced_dofs']} DOFs", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    save(fig, folder, "forced_response")


def figures():
    """{id: drawing function} from reproductions.txt, the one list of the reproductions."""
    report = _load("report", Path(__file__).with_name("report.py"))
    return {fid: globals()[figure] for _, fid, figure in report.reproductions() if figure is not None}


def draw(job):
    """Draws one reproduction's figures, job = (id, folder); returns the line to print."""
    fid, folder = job
    if not (folder / "meta.json").exists():
        return f"plot.py: {fid}: no results in {folder}, skipped"
    FIGURES[fid](folder)
    return f"plot.py: {fid}: figures written to {folder}"


FIGURES = {}


def main():
    """Each reproduction's figures are independent (each writes only into its own folder; one
    also reads jl14_fig12's CSV, written before this runs), so they are drawn by one process per
    core this process may use. One after the other they took 68 s of one core at the end of
    `make reproduce` while the other idled, and 36 s so on 2 cores (stop 63)."""
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
    plt.rcParams.update(STYLE)
    FIGURES.update(figures())
    jobs = [(fid, out / fid) for fid in FIGURES]
    workers = max(1, min(len(jobs), len(os.sched_getaffinity(0))))
    # fork: the workers inherit FIGURES and the style; the lines print in the list's order.
    with multiprocessing.get_context("fork").Pool(workers) as pool:
        for line in pool.imap(draw, jobs):
            print(line, flush=True)


if __name__ == "__main__":
    main()
