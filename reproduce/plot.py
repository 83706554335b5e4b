#!/usr/bin/env python3
"""Renders every known figure of out/ to PNG and PDF beside its CSV. The only plotting code.

Usage: plot.py OUT_DIR. Each figure id maps to a short function that reads the CSV, labels the
axes from its header (units in brackets) and applies one shared style. Figures whose folder is
missing are skipped with a note (a failed run writes no folder).
"""
import csv
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {"figure.figsize": (6.4, 4.0), "axes.grid": True, "grid.alpha": 0.3, "font.size": 10,
         "legend.fontsize": 8, "savefig.dpi": 150}
LABELS = {"bdf": "time stepping (BDF)", "fourier_fourier": "Fourier:Fourier"}


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], [[float(x) for x in r] for r in rows[1:]]
    return header, [list(col) for col in zip(*data)]


def save(fig, folder, stem):
    for ext in ("png", "pdf"):
        fig.savefig(folder / f"{stem}.{ext}", bbox_inches="tight")
    plt.close(fig)


def tip_displacement(folder):
    header, cols = read_csv(folder / "tip_displacement.csv")
    meta = json.loads((folder / "meta.json").read_text())
    fig, ax = plt.subplots()
    for name, col in zip(header[1:], cols[1:]):
        key = name.split(" ")[0].removeprefix("u_tip_")
        style = {"color": "k", "lw": 2.0, "alpha": 0.5} if key == "bdf" else {"lw": 1.0}
        label = LABELS.get(key, key.replace("_", ":"))
        if key != "bdf":
            label += f", M = {meta['figure_dimension']}"
        ax.plot(cols[0], [1e3 * v for v in col], label=label, **style)
    ax.axhline(1e3 * meta["gap_m"], color="r", ls=":", lw=1.0, label="gap $g_0$")
    ax.set_xlabel("normalized time τ [-]")
    ax.set_ylabel("tip displacement [mm]")
    ax.set_title(meta["scene"]["title"])
    ax.legend(loc="best")
    save(fig, folder, "tip_displacement")

    header, cols = read_csv(folder / "convergence.csv")
    fig, ax = plt.subplots()
    ax.loglog(cols[0], cols[1], "o-", label="Fourier:Fourier")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("number of basis functions M [-]")
    ax.set_ylabel("rms relative tip error [-]")
    ax.set_title(meta["scene"]["title"] + ": error against BDF")
    ax.legend()
    save(fig, folder, "convergence")


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


FIGURES = {"jl14_fig02": basis_functions, "jl14_fig03": basis_functions, "jl14_fig04": basis_functions,
           "jl14_fig05": basis_functions, "jl14_fig06": tip_displacement, "jl14_fig07": tip_displacement}


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
    plt.rcParams.update(STYLE)
    for fid, fn in FIGURES.items():
        folder = out / fid
        if not (folder / "meta.json").exists():
            print(f"plot.py: {fid}: no results in {folder}, skipped")
            continue
        fn(folder)
        print(f"plot.py: {fid}: figures written to {folder}")


if __name__ == "__main__":
    main()
