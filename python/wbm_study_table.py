"""The summary quantities of a study's cases, its table (study.csv) and its pictures (study.png)
(issue #37; docs/studies.md). Every number comes from a case folder's files: result.json and the
CSV tables `wbm run` wrote (docs/scenes.md, "Output files").

Quantities (the study file's `collect`):
- wall_time [s]: the case's `wbm run` on its worker (start to exit).
- folds [-]: the rows of folds.csv (continuation, nnm); empty without one.
- points [-]: the rows of the response table (branch.csv or frequency_response.csv).
- peak_amplitude[:DOF] [m], peak_frequency[:DOF] [Hz]: the largest amplitude of DOF over the
  response table and its frequency. The amplitude is branch.csv's `amplitude_<dof>`, or
  (max_u − min_u)/2 from frequency_response.csv; DOF defaults to the table's first.
- max:COLUMN, min:COLUMN (or max:FILE.csv:COLUMN): the largest or smallest value of a column of
  any CSV, COLUMN its header with or without the unit, e.g. max:max_contact_force.
A quantity a case does not have (a solve has no folds; a case that failed has no files) is an
empty cell; the row's status says why.
"""
import csv
import io
import json
import math
import os
from pathlib import Path

RESPONSE_TABLES = ("branch.csv", "frequency_response.csv")


def read_csv(data):
    """(header, rows as lists of str) of CSV bytes."""
    rows = list(csv.reader(io.StringIO(data.decode())))
    return (rows[0], rows[1:]) if rows else ([], [])


def _float(cell):
    try:
        v = float(cell)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def _name_unit(header):
    name, _, unit = header.partition(" [")
    return name, unit.rstrip("]") if unit else ""


def _column(header, rows, name):
    for j, h in enumerate(header):
        if h == name or _name_unit(h)[0] == name:
            return h, [_float(r[j]) for r in rows if j < len(r)]
    return None, None


def _response(files, dof):
    """(frequencies, amplitudes, dof name) of the response table, or None."""
    for table in RESPONSE_TABLES:
        if table not in files:
            continue
        header, rows = read_csv(files[table])
        names = [_name_unit(h)[0] for h in header]
        dofs = [n[len("amplitude_"):] for n in names if n.startswith("amplitude_")]
        dofs += [n[len("max_u_"):] for n in names if n.startswith("max_u_")]
        if not dofs:
            continue
        d = dof or dofs[0]
        _, freq = _column(header, rows, "frequency")
        _, amp = _column(header, rows, f"amplitude_{d}")
        if amp is None:
            _, hi = _column(header, rows, f"max_u_{d}")
            _, lo = _column(header, rows, f"min_u_{d}")
            if hi is None or lo is None:
                return None
            amp = [None if a is None or b is None else 0.5 * (a - b) for a, b in zip(hi, lo)]
        return freq, amp, d
    return None


def quantity_headers(collect, files_of_first):
    """Column headers (with units) of the quantities, named after the first case that has them."""
    headers = []
    for q in collect:
        name, _, arg = q.partition(":")
        if name == "wall_time":
            headers.append("wall_time [s]")
        elif name in ("folds", "points"):
            headers.append(f"{name} [-]")
        elif name in ("peak_amplitude", "peak_frequency"):
            dof = arg
            if not dof and files_of_first is not None:
                r = _response(files_of_first, "")
                dof = r[2] if r else ""
            unit = "m" if name == "peak_amplitude" else "Hz"
            headers.append(f"{name}_{dof} [{unit}]" if dof else f"{name} [{unit}]")
        else:
            column = arg.split(":")[-1]
            unit = ""
            if files_of_first is not None:
                h = _find_column(files_of_first, arg)[0]
                unit = _name_unit(h)[1] if h else ""
            headers.append(f"{name}_{_name_unit(column)[0]} [{unit or '-'}]")
    return headers


def _find_column(files, arg):
    file, _, column = arg.rpartition(":")
    for name in ([file] if file else sorted(files)):
        if name.endswith(".csv") and name in files:
            header, rows = read_csv(files[name])
            h, values = _column(header, rows, column)
            if h is not None:
                return h, values
    return None, None


def quantities(collect, files, wall_time_s):
    """The values of `collect` for one case (None where missing)."""
    out = []
    for q in collect:
        name, _, arg = q.partition(":")
        value = None
        if name == "wall_time":
            value = wall_time_s
        elif name == "folds":
            if "folds.csv" in files:
                value = float(len(read_csv(files["folds.csv"])[1]))
        elif name == "points":
            for t in RESPONSE_TABLES:
                if t in files:
                    value = float(len(read_csv(files[t])[1]))
                    break
        elif name in ("peak_amplitude", "peak_frequency"):
            r = _response(files, arg)
            if r and r[1]:
                pairs = [(a, f) for a, f in zip(r[1], r[0]) if a is not None and f is not None]
                if pairs:
                    a, f = max(pairs, key=lambda p: p[0])
                    value = a if name == "peak_amplitude" else f
        else:
            values = [v for v in (_find_column(files, arg)[1] or []) if v is not None]
            if values:
                value = max(values) if name == "max" else min(values)
        out.append(value)
    return out


def folder_files(folder):
    """{name: bytes} of a case folder's CSV files."""
    return {p.name: p.read_bytes() for p in sorted(Path(folder).glob("*.csv"))}


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ""
    if isinstance(v, (dict, list, bool)):  # a table or list value of an axis, as JSON
        return json.dumps(v, sort_keys=True)
    return str(v)


def write_table(path, header, rows):
    """study.csv: header row with units, %.17g-exact floats (repr), empty cells for missing values;
    written to a temporary name and renamed."""
    tmp = Path(path).with_name(f".{Path(path).name}.tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow([_cell(v) for v in r])
    os.replace(tmp, path)


def write_json(path, data):
    tmp = Path(path).with_name(f".{Path(path).name}.tmp")
    tmp.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")
    os.replace(tmp, path)


def draw(path, axes, header, rows, quantity_columns):
    """study.png: each numeric quantity against each axis (a dot per case, failed cases left out);
    with a random axis, a histogram of each quantity below. Returns a line saying what was drawn,
    or why not (matplotlib missing): pictures are extras and never fail a study."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return "study.png skipped: matplotlib is not available (install python3-matplotlib)"
    qs = [c for c in quantity_columns if any(isinstance(r[c], float) for r in rows)]
    if not qs:
        return "study.png skipped: no numeric quantity to draw"
    random = any(a["kind"] == "random" for a in axes)
    n_rows, n_cols = len(qs), len(axes) + (1 if random else 0)
    fig, grid = plt.subplots(n_rows, n_cols, figsize=(3.6 * n_cols, 2.8 * n_rows), squeeze=False)
    for i, c in enumerate(qs):
        for j, a in enumerate(axes):
            ax = grid[i][j]
            pts = [(r[1 + j], r[c]) for r in rows if isinstance(r[c], float) and isinstance(r[1 + j], (int, float))]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", ms=3)
            ax.set_xlabel(header[1 + j])
            ax.set_ylabel(header[c])
            if a["kind"] == "range" and a["spec"].get("spacing") == "log":
                ax.set_xscale("log")
        if random:
            ax = grid[i][-1]
            ax.hist([r[c] for r in rows if isinstance(r[c], float)], bins="auto")
            ax.set_xlabel(header[c])
            ax.set_ylabel("cases")
    fig.tight_layout()
    tmp = Path(path).with_name(".study.tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, path)
    return f"drew {Path(path).name}"
