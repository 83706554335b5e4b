"""Parametric and Monte Carlo studies of wbm scenes on Dask (issue #37; docs/studies.md).

A study file (TOML) names a base scene, axes over its keys and the summary quantities to collect:

    scene = "rod.toml"                  # relative to the study file; or an inline [scene] table
    combine = "product"                 # or "zip": the i-th value of every axis together
    collect = ["peak_amplitude", "peak_frequency", "folds", "max:max_contact_force"]

    [[axis]]
    key = "contact.gap"                 # a dotted scene key; contact[3].gap for one [[contact]]
    range = { from = 1e-3, to = 2e-3, points = 5, spacing = "linear" }   # or "log"
    # values = [1e-3, 2e-3]
    # random = { distribution = "normal", mean = 1.5e-3, std = 1e-4, samples = 20, seed = 1 }
    unit = "m"                          # written into the study table's header

Every case is the base scene with the axes' values set (a key on an array of tables, such as
`contact.gap`, sets every entry), resolved and validated by the scene parser (wbm.scene_json, the
parser of `wbm check`) before anything runs: a bad axis is refused with the key's own message and
nothing is written. A case is named by the SHA-256 of its resolved scene (16 hex digits), and runs
as `wbm run case.json --no-plots -q` on a Dask worker, so that its files equal those of a serial
`wbm run` of the same scene bit for bit. Its result folder, `cases/<id>/` (the files of `wbm run`,
`scene.json` and `case.json`), is written by the client, staged and renamed into place; a study
run again skips the cases whose folders exist. A case whose run does not converge is a row with
its status; a worker that dies has its case rerun on another (Dask reschedules it, up to
`retries` deaths); a case that still fails, or whose `wbm run` was killed (a signal, or
`case_timeout_s`), is a row with its status and no folder, run again on the next resume.

Outputs of a study folder: study.csv (one row per case: `case`, the axes' keys, `status`, the
summary quantities with their units, `message`; an empty cell where a quantity does not exist),
study.json (the study, the cases, timings), study.png (each quantity against each axis; for a
study with a random axis, histograms), and cases/.

Exit status of the command (`wbm study`, `python3 -m wbm_study`): 0 every case converged, 1 some
did not (or failed), 2 bad input (nothing written), 130 interrupted (the finished cases stay).
"""
import argparse
import copy
import hashlib
import itertools
import json
import math
import os
import re
import shutil
import sys
import time
import tomllib
from pathlib import Path

import wbm_study_table as table

STUDY_KEYS = ("title", "scene", "combine", "collect", "axis", "retries", "case_timeout_s")
AXIS_KEYS = ("key", "values", "range", "random", "unit")
DISTRIBUTIONS = {"uniform": ("low", "high"), "normal": ("mean", "std"), "lognormal": ("median", "sigma")}
BUILTIN_QUANTITIES = ("wall_time", "folds", "points", "peak_amplitude", "peak_frequency")
SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")
EXIT_CONVERGED, EXIT_NOT_CONVERGED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


class StudyError(ValueError):
    """A bad study file or axis: the message names the key, its value, what is allowed and a way out."""


# --- the study file -----------------------------------------------------------------------------

def _number(where, value, positive=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise StudyError(f"{where} = {value!r}: expected a finite number")
    if positive and value <= 0:
        raise StudyError(f"{where} = {value!r}: expected a number > 0")
    return float(value)


def _count(where, value):
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 1_000_000:
        raise StudyError(f"{where} = {value!r}: expected an integer in 1 … 1000000")
    return value


def parse_key(key):
    """'contact[3].gap' -> [('contact', 3), ('gap', None)]; StudyError for another form."""
    if not isinstance(key, str) or not key:
        raise StudyError(f"axis key = {key!r}: expected a dotted scene key such as \"contact.gap\" or "
                         "\"contact[3].gap\" (docs/scenes.md lists the keys)")
    parts = []
    for segment in key.split("."):
        m = SEGMENT.match(segment)
        if not m:
            raise StudyError(f"axis key = {key!r}: segment {segment!r} is not a key name with an optional "
                             "[index] (for example contact[3].gap)")
        parts.append((m.group(1), None if m.group(2) is None else int(m.group(2))))
    return parts


def axis_values(axis, where):
    """The values of one [[axis]] table: `values`, a `range` or `random` draws (numpy, seeded)."""
    given = [k for k in ("values", "range", "random") if k in axis]
    if len(given) != 1:
        raise StudyError(f"{where}: give exactly one of values, range, random (got {given or 'none'})")
    kind = given[0]
    spec = axis[kind]
    if kind == "values":
        if not isinstance(spec, list) or not spec:
            raise StudyError(f"{where}.values = {spec!r}: expected a non-empty list")
        return kind, list(spec)
    if not isinstance(spec, dict):
        raise StudyError(f"{where}.{kind} = {spec!r}: expected a table")
    import numpy as np  # only for ranges and draws
    if kind == "range":
        unknown = set(spec) - {"from", "to", "points", "spacing"}
        if unknown:
            raise StudyError(f"{where}.range: unknown key {sorted(unknown)[0]!r}; allowed: from, to, points, spacing")
        lo, hi = _number(f"{where}.range.from", spec.get("from")), _number(f"{where}.range.to", spec.get("to"))
        n = _count(f"{where}.range.points", spec.get("points"))
        spacing = spec.get("spacing", "linear")
        if spacing == "linear":
            return kind, [float(v) for v in np.linspace(lo, hi, n)]
        if spacing == "log":
            if lo <= 0 or hi <= 0:
                raise StudyError(f"{where}.range: spacing = \"log\" needs from > 0 and to > 0 (got {lo!r}, {hi!r}); "
                                 "use spacing = \"linear\"")
            return kind, [float(v) for v in np.geomspace(lo, hi, n)]
        raise StudyError(f"{where}.range.spacing = {spacing!r}: expected \"linear\" or \"log\"")
    dist = spec.get("distribution")
    if dist not in DISTRIBUTIONS:
        raise StudyError(f"{where}.random.distribution = {dist!r}: expected one of {', '.join(DISTRIBUTIONS)}")
    a, b = DISTRIBUTIONS[dist]
    allowed = {"distribution", "samples", "seed", a, b}
    unknown = set(spec) - allowed
    if unknown:
        raise StudyError(f"{where}.random: unknown key {sorted(unknown)[0]!r}; allowed for {dist}: "
                         f"{', '.join(sorted(allowed))}")
    n = _count(f"{where}.random.samples", spec.get("samples"))
    seed = spec.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise StudyError(f"{where}.random.seed = {seed!r}: expected an integer ≥ 0")
    pa = _number(f"{where}.random.{a}", spec.get(a))
    pb = _number(f"{where}.random.{b}", spec.get(b), positive=(dist != "uniform"))
    if dist == "uniform" and not pa < pb:
        raise StudyError(f"{where}.random: uniform needs low < high (got {pa!r}, {pb!r})")
    rng = np.random.default_rng(seed)
    if dist == "uniform":
        draws = rng.uniform(pa, pb, n)
    elif dist == "normal":
        draws = rng.normal(pa, pb, n)
    else:  # median · exp(σ z): the median and the standard deviation of the logarithm
        if pa <= 0:
            raise StudyError(f"{where}.random.median = {pa!r}: expected a number > 0")
        draws = pa * np.exp(pb * rng.standard_normal(n))
    return kind, [float(v) for v in draws]


def _load_scene_file(path, where):
    path = Path(path)
    if not path.is_file():
        raise StudyError(f"{where} = \"{path}\": no such file (paths are relative to the study file)")
    if path.suffix == ".json":
        try:
            data = json.loads(path.read_text())
        except ValueError as e:
            raise StudyError(f"{path}: JSON syntax: {e}") from None
        if not isinstance(data, dict):
            raise StudyError(f"{path}: expected a JSON object holding a scene (or a result.json)")
        return data.get("scene", data)
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise StudyError(f"{path}: TOML syntax: {e}") from None


def load_study(source):
    """A study from a TOML file path or a dict (the same keys). Returns a dict with the base scene
    (raw, as written), the file that anchors its relative paths, the axes and the collect list."""
    if isinstance(source, dict):
        data, origin, anchor = copy.deepcopy(source), "<study>", Path("<study>")  # paths relative to the cwd
    else:
        origin = str(source)
        path = Path(source)
        if not path.is_file():
            raise StudyError(f"study {origin}: no such file (give the path of a study .toml)")
        try:
            with open(path, "rb") as f:
                data = tomllib.load(f)
        except tomllib.TOMLDecodeError as e:
            raise StudyError(f"{origin}: TOML syntax: {e}") from None
        anchor = path.resolve()
    unknown = [k for k in data if k not in STUDY_KEYS]
    if unknown:
        raise StudyError(f"{origin}: {unknown[0]}: unknown key; allowed: {', '.join(STUDY_KEYS)}")
    scene = data.get("scene")
    if isinstance(scene, str):
        scene_file = (anchor.parent / scene).resolve() if origin != "<study>" else Path(scene).resolve()
        base = _load_scene_file(scene_file, f"{origin}: scene")
    elif isinstance(scene, dict):
        scene_file, base = anchor, scene
    else:
        raise StudyError(f"{origin}: scene = {scene!r}: expected a scene file path or an inline [scene] table")
    combine = data.get("combine", "product")
    if combine not in ("product", "zip"):
        raise StudyError(f"{origin}: combine = {combine!r}: expected \"product\" (every combination) or \"zip\"")
    axes_in = data.get("axis", [])
    if isinstance(axes_in, dict):
        axes_in = [axes_in]
    if not isinstance(axes_in, list) or not axes_in:
        raise StudyError(f"{origin}: no [[axis]]: give at least one axis (key and values, range or random)")
    axes = []
    for i, a in enumerate(axes_in):
        where = f"{origin}: axis[{i}]"
        if not isinstance(a, dict):
            raise StudyError(f"{where} = {a!r}: expected a table")
        bad = [k for k in a if k not in AXIS_KEYS]
        if bad:
            raise StudyError(f"{where}.{bad[0]}: unknown key; allowed: {', '.join(AXIS_KEYS)}")
        parse_key(a.get("key"))
        kind, values = axis_values(a, where)
        unit = a.get("unit", "")
        if not isinstance(unit, str):
            raise StudyError(f"{where}.unit = {unit!r}: expected a string such as \"m\"")
        axes.append({"key": a["key"], "kind": kind, "spec": a[kind], "unit": unit, "values": values})
    if combine == "zip" and len({len(a["values"]) for a in axes}) > 1:
        sizes = ", ".join(f"{a['key']}: {len(a['values'])}" for a in axes)
        raise StudyError(f"{origin}: combine = \"zip\" needs axes of one length (got {sizes}); "
                         "use combine = \"product\" or equal lengths")
    collect = data.get("collect", ["peak_amplitude", "peak_frequency"])
    if not isinstance(collect, list) or not all(isinstance(q, str) for q in collect):
        raise StudyError(f"{origin}: collect = {collect!r}: expected a list of quantity names")
    for q in collect:
        _check_quantity(q, origin)
    retries = data.get("retries", 3)
    if isinstance(retries, bool) or not isinstance(retries, int) or not 0 <= retries <= 100:
        raise StudyError(f"{origin}: retries = {retries!r}: expected an integer in 0 … 100 (worker deaths a case survives)")
    timeout = data.get("case_timeout_s", 0)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or timeout < 0:
        raise StudyError(f"{origin}: case_timeout_s = {timeout!r}: expected a number ≥ 0 (0: no limit)")
    title = data.get("title", Path(origin).stem if origin != "<study>" else "study")
    return {"origin": origin, "title": str(title), "scene_file": str(scene_file), "base": base,
            "combine": combine, "axes": axes, "collect": collect, "retries": retries,
            "case_timeout_s": float(timeout)}


def _check_quantity(q, origin):
    name, _, arg = q.partition(":")
    if name in ("max", "min"):
        if not arg:
            raise StudyError(f"{origin}: collect {q!r}: give the column, \"{name}:COLUMN\" or \"{name}:FILE.csv:COLUMN\"")
    elif name not in BUILTIN_QUANTITIES:
        raise StudyError(f"{origin}: collect {q!r}: unknown quantity; allowed: {', '.join(BUILTIN_QUANTITIES)} "
                         "(peak_* take an optional :DOF), max:COLUMN, min:COLUMN")


# --- cases --------------------------------------------------------------------------------------

def _assign(node, parts, value, key):
    (name, index), rest = parts[0], parts[1:]
    if not isinstance(node, dict):
        raise StudyError(f"axis key {key!r}: {name!r} is below a value that is not a table")
    if not rest:
        if index is None:
            node[name] = value
            return
        target = node.get(name)
        if isinstance(target, list) and index < len(target):
            target[index] = value
            return
        raise StudyError(f"axis key {key!r}: {name} has no entry [{index}]")
    child = node.get(name)
    if index is not None:
        if isinstance(child, list) and index < len(child):
            child = child[index]
        elif not (isinstance(child, dict) and index == 0):  # [contact] written as one table is [0]
            size = len(child) if isinstance(child, list) else (1 if isinstance(child, dict) else 0)
            raise StudyError(f"axis key {key!r}: the scene has {size} {name} table(s), so [{index}] does not exist "
                             f"(indices are 0-based)")
        _assign(child, rest, value, key)
        return
    if child is None:
        child = node[name] = {}
    if isinstance(child, list):  # every table of an array of tables
        for entry in child:
            _assign(entry, rest, value, key)
        return
    _assign(child, rest, value, key)


def scene_with(base, settings):
    """The base scene (raw dict) with each (key, value) of `settings` set."""
    scene = copy.deepcopy(base)
    for key, value in settings:
        _assign(scene, parse_key(key), value, key)
    return scene


def case_id(resolved):
    """The first 16 hex digits of the SHA-256 of the resolved scene's canonical JSON."""
    text = json.dumps(resolved, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def make_cases(study, resolve):
    """Every case of the study, resolved by `resolve(raw_scene, anchor_file)` (wbm.scene_json):
    [{"index", "parameters": {key: value}, "scene": resolved dict, "id"}]. A scene the parser
    refuses raises StudyError naming the case's values and the parser's message (file, key,
    allowed range, way out)."""
    axes = study["axes"]
    columns = [a["values"] for a in axes]
    combos = zip(*columns) if study["combine"] == "zip" else itertools.product(*columns)
    cases = []
    for i, combo in enumerate(combos):
        settings = [(a["key"], v) for a, v in zip(axes, combo)]
        raw = scene_with(study["base"], settings)
        try:
            resolved = resolve(raw, study["scene_file"])
        except ValueError as e:
            values = ", ".join(f"{k} = {v!r}" for k, v in settings)
            raise StudyError(f"{study['origin']}: case {i} ({values}): {e}") from None
        cases.append({"index": i, "parameters": dict(settings), "scene": resolved, "id": case_id(resolved)})
    return cases


def run_case(cli, scene_text, timeout_s):
    """On a worker: `wbm run scene.json -o out --no-plots -q` in a temporary folder. Returns the
    exit code, the last lines of its error output, its files {name: bytes} and its wall time [s].
    The worker's own WBM_CLI, if set, names its wbm executable (a cluster's install)."""
    import socket
    import subprocess
    import tempfile
    exe = os.environ.get("WBM_CLI") or cli
    with tempfile.TemporaryDirectory(prefix="wbm-case-") as tmp:
        scene = os.path.join(tmp, "scene.json")
        with open(scene, "w") as f:
            f.write(scene_text)
        out = os.path.join(tmp, "out")
        start = time.perf_counter()
        try:
            proc = subprocess.run([exe, "run", scene, "-o", out, "--no-plots", "-q"], capture_output=True,
                                  text=True, errors="replace", timeout=timeout_s or None)
            code, err = proc.returncode, proc.stderr
        except subprocess.TimeoutExpired:
            code, err = -9, f"case_timeout_s = {timeout_s:g} s reached; the run was stopped (raise case_timeout_s)"
        seconds = time.perf_counter() - start
        files = {}
        if os.path.isdir(out):
            for name in sorted(os.listdir(out)):
                p = os.path.join(out, name)
                if os.path.isfile(p):
                    with open(p, "rb") as f:
                        files[name] = f.read()
    lines = [l for l in err.splitlines() if l.strip()]
    return {"exit_code": code, "stderr": "\n".join(lines[-20:]), "files": files, "wall_time_s": seconds,
            "worker": f"{socket.gethostname()}:{os.getpid()}"}


def outcome_status(code):
    """The row status of a `wbm run` exit code (docs/scenes.md: 0, 1, 2; negative: a signal)."""
    if code == 0:
        return "converged"
    if code == 1:
        return "not converged"
    if code == 2:
        return "bad input"
    if code < 0:
        return f"killed by signal {-code}"
    return f"exit code {code}"


def _write_case(folder, case, outcome, study):
    """cases/<id>/: the run's files, scene.json and case.json, staged and renamed into place."""
    folder.mkdir(parents=True, exist_ok=True)
    final = folder / case["id"]
    staging = folder / f".{case['id']}.staging-{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    for name, data in outcome["files"].items():
        (staging / name).write_bytes(data)
    (staging / "scene.json").write_text(json.dumps(case["scene"], indent=2) + "\n")
    record = {"id": case["id"], "parameters": case["parameters"], "status": outcome_status(outcome["exit_code"]),
              "exit_code": outcome["exit_code"], "message": _message(outcome), "wall_time_s": outcome["wall_time_s"],
              "worker": outcome["worker"], "study": study["origin"]}
    (staging / "case.json").write_text(json.dumps(record, indent=2) + "\n")
    shutil.rmtree(final, ignore_errors=True)
    os.rename(staging, final)
    return record


def _message(outcome):
    """Why a case did not converge: result.json's solver status and its analysis' message, else
    the last line of the run's error output."""
    if outcome["exit_code"] == 0:
        return ""
    try:
        d = json.loads(outcome["files"]["result.json"])["diagnostics"]
        block = d.get(d.get("analysis", ""), {})
        text = (block.get("message") if isinstance(block, dict) else None) or d.get("message") or ""
        return f"{d.get('status', '')}: {text}" if text else str(d.get("status", ""))
    except (KeyError, ValueError, TypeError, AttributeError):
        lines = outcome["stderr"].splitlines()
        return lines[-1] if lines else "no error output"


# --- running ------------------------------------------------------------------------------------

def find_cli(cli=None):
    """The wbm executable the cases run: `cli`, else $WBM_CLI, else the build tree's or the install
    prefix's beside this file, else `wbm` on PATH. StudyError naming the places looked in."""
    here = Path(__file__).resolve().parent
    candidates = [cli, os.environ.get("WBM_CLI"), here.parent / "cli" / "wbm", here.parents[2] / "bin" / "wbm"
                  if len(here.parents) > 2 else None, shutil.which("wbm")]
    for c in candidates:
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return str(Path(c).resolve())
    raise StudyError("no wbm executable found (looked at the cli argument, $WBM_CLI, "
                     f"{here.parent / 'cli' / 'wbm'}, the install prefix and PATH): set WBM_CLI=/path/to/wbm")


def _resolver():
    import wbm  # the extension module: the scene parser of `wbm check`
    return lambda raw, anchor: wbm.scene_json(raw, anchor)


def _row(case, record, files, study):
    return ([case["id"]] + [case["parameters"][a["key"]] for a in study["axes"]] + [record["status"]] +
            table.quantities(study["collect"], files, record.get("wall_time_s")) + [record["message"]])


class _Progress:
    def __init__(self, total, quiet):
        self.total, self.done, self.quiet, self.start = total, 0, quiet, time.monotonic()

    def __call__(self, case, status, seconds, worker):
        self.done += 1
        if not self.quiet:
            print(f"[{self.done}/{self.total}] case {case['id']} {status} ({seconds:.1f} s on {worker}; "
                  f"{time.monotonic() - self.start:.0f} s elapsed)", file=sys.stderr, flush=True)


def _client(workers, scheduler, retries):
    """A Dask client: on `scheduler` (tcp://HOST:PORT), else on an embedded LocalCluster of
    `workers` single-threaded worker processes on 127.0.0.1 (default: one per core)."""
    import logging
    import dask
    from dask.distributed import Client, LocalCluster
    if scheduler:  # its own allowed-failures setting applies
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError) as e:
            raise StudyError(f"--scheduler {scheduler}: cannot connect ({e}); start one with `dask-scheduler`, "
                             "or leave --scheduler out for a local cluster") from None
    n = workers or os.cpu_count() or 1
    with dask.config.set({"distributed.scheduler.allowed-failures": retries}):  # read when the scheduler starts
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_study(source, output=None, workers=None, scheduler=None, quiet=True, cli=None):
    """Runs a study (a .toml path or a dict) into `output` (default wbm-study/<title>). Returns
    (header, rows, summary): the rows of study.csv (one per case, in case order) and study.json's
    content. Raises StudyError for bad input before anything is written; KeyboardInterrupt
    leaves the finished cases in place (a rerun resumes)."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise StudyError(f"workers = {workers!r}: expected an integer ≥ 1 (worker processes of the local cluster)")
    if workers is not None and scheduler:
        raise StudyError("workers and scheduler given together: the scheduler's cluster has its own workers; "
                         "give one of them")
    study = load_study(source)
    exe = find_cli(cli)
    cases = make_cases(study, _resolver())
    out = Path(output) if output else Path("wbm-study") / study["title"]
    if out.exists() and not out.is_dir():
        raise StudyError(f"-o {out}: exists and is not a folder; give another output folder")
    folder = out / "cases"
    unique = {}
    for c in cases:
        unique.setdefault(c["id"], c)
    todo = [c for c in unique.values() if not (folder / c["id"] / "case.json").is_file()]
    client = cluster = None
    cluster_start_s = 0.0
    if todo:  # connected before anything is written: a bad --scheduler writes nothing
        import cloudpickle
        if run_case.__module__ != "__main__":  # remote workers need not have this file
            cloudpickle.register_pickle_by_value(sys.modules[run_case.__module__])
        started = time.monotonic()
        client, cluster = _client(workers, scheduler, study["retries"])
        cluster_start_s = time.monotonic() - started
    start = time.monotonic()
    outcomes, failures = {}, {}
    progress = _Progress(len(todo), quiet)
    n_workers = 0
    try:
        out.mkdir(parents=True, exist_ok=True)
        if not quiet:
            print(f"wbm study: {len(cases)} cases ({len(unique)} distinct scenes), {len(unique) - len(todo)} "
                  f"complete already, {len(todo)} to run", file=sys.stderr, flush=True)
        if client is not None:
            from dask.distributed import as_completed
            n_workers = len(client.scheduler_info()["workers"])
            futures = {client.submit(run_case, exe, json.dumps(c["scene"], indent=2) + "\n",
                                     study["case_timeout_s"], key=f"wbm-case-{c['id']}", pure=False): c for c in todo}
            for future in as_completed(futures):
                c = futures[future]
                try:
                    outcome = future.result()
                except Exception as e:  # a worker that died `retries` times, or the task itself
                    failures[c["id"]] = ("failed", f"{type(e).__name__}: {e}", None)
                    progress(c, "failed", 0.0, "-")
                    continue
                if outcome["exit_code"] not in (0, 1, 2):  # killed (a signal, case_timeout_s): no folder,
                    status = outcome_status(outcome["exit_code"])  # so that the next run tries it again
                    failures[c["id"]] = (status, _message(outcome), outcome["wall_time_s"])
                    progress(c, status, outcome["wall_time_s"], outcome["worker"])
                    continue
                outcomes[c["id"]] = _write_case(folder, c, outcome, study)
                progress(c, outcomes[c["id"]]["status"], outcome["wall_time_s"], outcome["worker"])
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    rows = []
    first_files = None
    for c in cases:
        if c["id"] in failures:
            status, message, seconds = failures[c["id"]]
            rows.append((c, {"status": status, "message": message, "wall_time_s": seconds}, {}))
            continue
        record = outcomes.get(c["id"]) or json.loads((folder / c["id"] / "case.json").read_text())
        files = table.folder_files(folder / c["id"])
        if first_files is None and files:
            first_files = files
        rows.append((c, record, files))
    header = (["case"] + [f"{a['key']} [{a['unit']}]" if a["unit"] else a["key"] for a in study["axes"]] +
              ["status"] + table.quantity_headers(study["collect"], first_files) + ["message"])
    table_rows = [_row(c, record, files, study) for c, record, files in rows]
    elapsed = time.monotonic() - start
    run_times = [outcomes[i]["wall_time_s"] for i in outcomes]
    summary = {
        "study": study["origin"], "title": study["title"], "scene_file": study["scene_file"],
        "combine": study["combine"], "collect": study["collect"],
        "axes": [{k: a[k] for k in ("key", "kind", "spec", "unit", "values")} for a in study["axes"]],
        "cases": len(cases), "distinct_scenes": len(unique), "run": len(outcomes), "failed": len(failures),
        "resumed": len(unique) - len(todo), "workers": n_workers, "scheduler": scheduler or "local",
        "cluster_start_s": cluster_start_s, "wall_time_s": elapsed, "case_run_time_s": sum(run_times),
        "overhead_per_case_s": (elapsed * n_workers - sum(run_times)) / len(run_times) if run_times else None,
        "wbm": exe, "table": {"header": header, "rows": table_rows}, "statuses": {s: sum(1 for r in table_rows if r[len(study['axes']) + 1] == s)
                                 for s in sorted({r[len(study['axes']) + 1] for r in table_rows})},
    }
    table.write_table(out / "study.csv", header, table_rows)
    table.write_json(out / "study.json", summary)
    q0 = len(study["axes"]) + 2
    drawn = table.draw(out / "study.png", study["axes"], header, table_rows, list(range(q0, q0 + len(study["collect"]))))
    if not quiet:
        print(f"wbm study: {drawn}; wrote study.csv, study.json and {len(unique)} case folders to {out} "
              f"in {elapsed:.1f} s", file=sys.stderr)
    return header, table_rows, summary


def study(source, output=None, workers=None, scheduler=None, quiet=True, cli=None):
    """Runs a study and returns its table as a pandas DataFrame (the columns of study.csv, units in
    the headers; NaN where a quantity is missing). `source`: a study .toml path or a dict of its
    keys; `output`: the study folder (default wbm-study/<title>); `workers`: local worker
    processes (default: one per core); `scheduler`: tcp://HOST:PORT of a running Dask scheduler,
    instead of the local cluster; `cli`: the wbm executable (default $WBM_CLI, the build tree's,
    or PATH's). Raises ValueError (StudyError) for a bad study, before any case runs."""
    try:
        import pandas
    except ImportError:
        raise ImportError("wbm.study returns a pandas DataFrame: install python3-pandas "
                          "(or run `wbm study`, which writes study.csv)") from None
    header, rows, _ = run_study(source, output, workers, scheduler, quiet, cli)
    return pandas.DataFrame([[float("nan") if v is None else v for v in r] for r in rows], columns=header)


def main(argv=None):
    p = argparse.ArgumentParser(prog="wbm study", description="Run a parametric or Monte Carlo study of a "
                                "scene on Dask: study.csv, study.json, study.png and one result folder per case.")
    p.add_argument("study", help="Study file (.toml); docs/studies.md")
    p.add_argument("-o", "--output", help="Study folder (default wbm-study/<title>); complete cases there are skipped")
    p.add_argument("--workers", type=int, help="Worker processes of the local cluster (default: one per core)")
    p.add_argument("--scheduler", help="tcp://HOST:PORT of a running Dask scheduler, instead of a local cluster")
    p.add_argument("-q", "--quiet", action="store_true", help="No progress lines")
    a = p.parse_args(argv)
    try:
        _, rows, summary = run_study(a.study, a.output, a.workers, a.scheduler, a.quiet)
    except StudyError as e:
        print(f"wbm study: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:  # a folder or file that cannot be written, a tool that cannot start
        print(f"wbm study: {e}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    except KeyboardInterrupt:
        print("wbm study: interrupted; the finished cases are kept, run the same command again to resume",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_CONVERGED if summary["statuses"] == {"converged": len(rows)} else EXIT_NOT_CONVERGED


if __name__ == "__main__":
    sys.exit(main())
