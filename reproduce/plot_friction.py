"""The friction figures of reproductions.txt (issue #36), drawn by plot.py: the 1-DOF damper
against Den Hartog with the Jenkins element and with exact Coulomb friction, the chain under a
varying normal load, and the point rubbing on a rigid plane (a 2D contact)."""
import json
import math

from plot_common import MARKERS, plt, save, wbm_plot


def friction_den_hartog(folder):
    """Issue #36: (a) the damper's amplitude against r, Den Hartog's closed form and every pair at
    the stiffest k_t; (b) one period of the stick-slip motion, the exact motions and each pair."""
    meta = json.loads((folder / "meta.json").read_text())
    labels = meta["combinations"]
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    ax = axes[0]
    table = wbm_plot.read_csv(folder / "frf.csv")
    top = max(meta["kt_over_k"])
    rows = [i for i, kt in enumerate(table["kt_over_k [-]"]) if kt == top and table["combination [-]"][i] == 0]
    r = [table["r [-]"][i] for i in rows]
    static = meta["force_N"] / meta["stiffness_N_per_m"]
    for side in (lambda x: x < 1.0, lambda x: x > 1.0):
        pts = [(x, table["den_hartog [m]"][i] / static) for x, i in zip(r, rows) if side(x)]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "k-", lw=1.4,
                label="Den Hartog (closed form, at the r computed)" if side(0.5) else None)
    for c, label in enumerate(labels):
        idx = [i for i, kt in enumerate(table["kt_over_k [-]"]) if kt == top and table["combination [-]"][i] == c
               and math.isfinite(table["amplitude [m]"][i])]
        if not idx:
            continue  # not solved (its status is in frf.csv and the report)
        ax.plot([table["r [-]"][i] for i in idx], [table["amplitude [m]"][i] / static for i in idx], MARKERS[c],
                ms=5, mfc="none", label=f"{label}, k_t = {top:g} k")
    ax.set_yscale("log")
    ax.set_xlabel("r = ω/ω_n [-]")
    ax.set_ylabel("amplitude / (P/k) [-]")
    ax.set_title(f"(a) undamped, F0/P = {meta['a']['slip_force_N'] / meta['force_N']:g}, M = {meta['a']['dimension']}",
                 fontsize=9)
    ax.legend(fontsize=7)
    def curves(ax, hist, tau):
        for name in hist:
            if name.startswith("jenkins_exact_kt"):
                ax.plot(tau, hist[name], "--", lw=0.9, label=f"exact Jenkins, k_t = {name[16:].split(' ')[0]} k")
        for name in hist:
            if "_kt" in name and not name.startswith("jenkins"):
                ax.plot(tau, hist[name], lw=0.8, label=name.replace(" [m]", "").replace("_kt", ", k_t = ") + " k")
    _stick_slip_panel(axes[1], folder, meta, curves)
    fig.tight_layout()
    save(fig, folder, "friction")


def _stick_slip_panel(ax, folder, meta, curves):
    """Panel (b) of the friction figures: one period of history.csv, the event-driven Coulomb
    motion in black and the other columns drawn by curves(ax, hist, tau)."""
    hist = wbm_plot.read_csv(folder / "history.csv")
    tau = hist["tau [-]"]
    ax.plot(tau, hist["coulomb [m]"], "k-", lw=1.6, label="Coulomb, event-driven")
    curves(ax, hist, tau)
    ax.set_xlabel("τ = t/T [-]")
    ax.set_ylabel("x [m]")
    ax.set_title(f"(b) stick–slip, ζ = {meta['b']['zeta']:g}, r = {meta['b']['r']:g}, "
                 f"M = {meta['b']['history_dimension']}", fontsize=9)
    ax.legend(fontsize=6)


def friction_coulomb_exact(folder):
    """Issue #36, exact Coulomb friction: (a) the largest error against Den Hartog versus M, per
    pair; (b) one period of the stick-slip motion, the event-driven reference and each pair."""
    meta = json.loads((folder / "meta.json").read_text())
    labels = meta["combinations"]
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    ax = axes[0]
    dims = meta["a"]["dimensions"]
    for c, label in enumerate(labels):
        errors = meta["a"]["largest_error_den_hartog"][c]
        pts = [(m, e) for m, e in zip(dims, errors) if e is not None and math.isfinite(e) and e > 0]
        if pts:
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], MARKERS[c] + "-", ms=5, mfc="none", lw=0.8,
                      label=f"{label} (order {meta['a']['orders'][c]:.2f})" if meta["a"]["orders"][c] is not None
                      else label)
    ax.set_xlabel("M [-]")
    ax.set_ylabel("largest |x_max / Den Hartog - 1| [-]")
    ax.set_title(f"(a) undamped, F0/P = {meta['a']['slip_force_N'] / meta['force_N']:g}, "
                 f"{len(meta['a']['ratios'])} frequency ratios", fontsize=9)
    ax.legend(fontsize=7)
    def curves(ax, hist, tau):
        for name in hist:
            if name not in ("tau [-]", "coulomb [m]"):
                ax.plot(tau, hist[name], lw=0.8, label=name.replace(" [m]", ""))
    _stick_slip_panel(axes[1], folder, meta, curves)
    fig.tight_layout()
    save(fig, folder, "friction_exact")


def _errors_versus_m(ax, meta, key, ylabel, title):
    """Panel: the rms error `meta[key]` (one list per pair, over meta["dimensions"]) versus M on log
    axes, each pair with its fitted order, and the reference's own error as a dotted line."""
    for c, label in enumerate(meta["combinations"]):
        pts = [(m, e) for m, e in zip(meta["dimensions"], meta[key][c]) if e is not None and math.isfinite(e) and e > 0]
        if pts:
            order = meta["orders"][c]
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], MARKERS[c] + "-", ms=5, mfc="none", lw=0.8,
                      label=f"{label} (order {order:.2f})" if order is not None else label)
    ax.axhline(meta["reference_self_error"], color="k", ls=":", lw=0.8, label="reference's own error")
    ax.set_xlabel("M [-]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)


def _history(ax, folder, meta, reference, reference_label, ylabel):
    """Panel: one period of history.csv, the reference column `reference` and each pair's."""
    hist = wbm_plot.read_csv(folder / "history.csv")
    tau = hist["tau [-]"]
    ax.plot(tau, hist[reference], "k-", lw=1.6, label=reference_label)
    for name in hist:
        if name not in ("tau [-]", reference):
            ax.plot(tau, hist[name], lw=0.8, label=name.replace(" [m]", ""))
    ax.set_xlabel("τ = t/T [-]")
    ax.set_ylabel(ylabel)
    ax.set_title(f"(b) M = {meta['history_dimension']}", fontsize=9)
    ax.legend(fontsize=6)


def friction_normal_load(folder):
    """Issue #36, a varying normal load: (a) the rms error of x3 against the central-difference
    reference versus M, per pair, with the reference's own error; (b) one period of x3, the
    reference and each pair; (c) the reference's normal and friction forces and the bound ±μ n."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(1, 3, figsize=(15.0, 4.2))
    _errors_versus_m(axes[0], meta, "errors_x3", "rms error of x3 / rms x3 [-]",
                     f"(a) {meta['frequency_hz']:g} Hz, Q = {meta['time_samples']}")
    _history(axes[1], folder, meta, "reference [m]", "central differences", "x3 [m]")
    ref = wbm_plot.read_csv(folder / "reference.csv")
    ax = axes[2]
    mu = meta["friction_coefficient"]
    ax.plot(ref["tau [-]"], ref["normal_force [N]"], "k-", lw=1.2, label="normal force n")
    ax.plot(ref["tau [-]"], ref["friction_force [N]"], "C3-", lw=1.2, label="friction force f_t")
    ax.plot(ref["tau [-]"], [mu * n for n in ref["normal_force [N]"]], "C3:", lw=0.8, label="±μ n")
    ax.plot(ref["tau [-]"], [-mu * n for n in ref["normal_force [N]"]], "C3:", lw=0.8)
    ax.set_xlabel("τ = t/T [-]")
    ax.set_ylabel("force [N]")
    ax.set_title(f"(c) reference: stick {100.0 * meta['stick_fraction']:.1f} % of the period", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, folder, "friction_normal_load")


def friction_rigid_normal(folder):
    """Issue #36, a 2D contact (exact Coulomb friction on a rigid stop): (a) the rms error of x
    against Moreau-Jean with Siconos' fc2d versus M, per pair, with the reference's own error;
    (b) one period of x, the reference and each pair."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    _errors_versus_m(axes[0], meta, "errors_x", "rms error of x / rms x [-]",
                     f"(a) {meta['frequency_hz']:g} Hz, normal load {meta['static_normal_load_N']:g} ± "
                     f"{meta['normal_swing_N']:g} N")
    _history(axes[1], folder, meta, "moreau_jean [m]", "Moreau-Jean (Siconos fc2d)", "x [m]")
    fig.tight_layout()
    save(fig, folder, "friction_rigid_normal")


def friction_oval_casing(folder):
    """Issue #36: (a) the blade's amplitude against f/f1 (the rotation speed), rubbing an oval
    casing with and without friction; (b) where the frictional amplitude is largest, the first tip
    node's radial and friction forces over the period, and its gap."""
    meta = json.loads((folder / "meta.json").read_text())
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    ax = axes[0]
    for file, label, style in (("frictionless.csv", "frictionless", "k-"),
                               ("friction.csv", f"μ = {meta['friction_coefficient']:g}", "C3-")):
        table = wbm_plot.read_csv(folder / file)
        ax.plot(table["f_over_f1 [-]"], table["amplitude [gap]"], style, lw=1.2, label=label)
    ax.set_xlabel(f"f / f1 = {meta['lobes']} Ω / (2π f1) [-]")
    ax.set_ylabel("circumferential amplitude [gap]")
    ax.set_title(f"(a) {meta['lobes']} lobes, δ = {meta['ovalization_m'] / meta['gap_m']:g} gaps, "
                 f"Fourier:Fourier H = {meta['harmonics']}", fontsize=9)
    ax.legend(fontsize=8)
    ax = axes[1]
    peak = wbm_plot.read_csv(folder / "orbit.csv")
    ax.plot(peak["tau [-]"], peak["normal_force [N]"], "k-", lw=1.0, label="radial force f_n")
    ax.plot(peak["tau [-]"], peak["friction_force [N]"], "C3--", lw=1.0, label="friction force f_t")
    ax.set_xlabel("τ = f t [-]")
    ax.set_ylabel("force [N]")
    gap = ax.twinx()
    gap.plot(peak["tau [-]"], [g * 1e6 for g in peak["gap [m]"]], "C0:", lw=0.9, label="gap")
    gap.set_ylabel("gap [µm]")
    ratio = meta["largest_amplitude_frequency_hz"][1] / meta["f1_hz"]
    ax.set_title(f"(b) at the largest frictional amplitude, f/f1 = {ratio:.4f}", fontsize=9)
    lines = ax.get_legend_handles_labels()
    more = gap.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8)
    fig.tight_layout()
    save(fig, folder, "friction_oval_casing")
