"""The pieces the reproduction figures share (plot.py, plot_friction.py, plot_impacts.py): the module
loader, the matplotlib and CSV reader of `wbm run`'s pictures (cli/wbm_plot.py, loaded from the
source tree), the style, the labels and markers of the Table 2 pairs, the writer of PNG and PDF, and
column(), one named column of a CSV."""
import importlib.util
from pathlib import Path


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# matplotlib with the Agg backend, the CSV reader and the style (it exits 3 without matplotlib).
wbm_plot = _load("wbm_plot", Path(__file__).resolve().parents[1] / "cli" / "wbm_plot.py")
plt = wbm_plot.plt
STYLE = wbm_plot.STYLE
LABELS = {"bdf": "time stepping (BDF)", "fourier_fourier": "Fourier:Fourier", "bspline_bspline": "B-spline:B-spline",
          "db6_db6": "DB6:DB6", "haar_fourier": "Haar:Fourier", "db6_fourier": "DB6:Fourier",
          "haar_bspline": "Haar:B-spline"}
# Table 2 order (the combination index of the sweep tables), then BDF.
METHODS = ["Fourier:Fourier", "B-spline:B-spline", "DB6:DB6", "Haar:Fourier", "DB6:Fourier", "Haar:B-spline", "BDF"]
MARKERS = ["o", "s", "^", "v", "D", "<", "x"]


def read_csv(path):
    """Numeric columns of a result CSV (wbm_plot.read_csv) as (header, columns); an empty cell (a
    missing value) reads as NaN, and the text column "status", which says why a value is missing,
    is left out (read_status)."""
    table = wbm_plot.read_csv(path)
    header = [name for name in table if name != "status"]
    return header, [table[name] for name in header]


def read_status(path):
    """The "status" column of a result CSV (empty list if it has none)."""
    return wbm_plot.read_csv(path).get("status", [])


def save(fig, folder, stem):
    for ext in ("png", "pdf"):
        fig.savefig(folder / f"{stem}.{ext}", bbox_inches="tight")
    plt.close(fig)


def column(folder, file, name):
    header, cols = read_csv(folder / file)
    return cols[header.index(name)]


def label_grid_panel(ax, i, key, ylabel):
    """Panel i of a 2 x 3 grid of the Table 2 combinations: "(a) Fourier:Fourier" as its title,
    its legend, the time axis' label on the bottom row and `ylabel` on the left column."""
    ax.set_title(f"({'abcdef'[i]}) {LABELS[key]}", fontsize=9)
    ax.legend(loc="best", fontsize=6)
    if i >= 3:
        ax.set_xlabel("normalized time τ [-]")
    if i % 3 == 0:
        ax.set_ylabel(ylabel)
