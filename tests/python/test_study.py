"""Studies on Dask (issue #37): wbm.study and `wbm study` against real Dask processes on 127.0.0.1.

Run by `make test` (python.pytest, with PYTHONPATH=<build>/python and WBM_CLI=<build>/cli/wbm). The
truths: the table's values against a closed form (a linear oscillator's receptance) and against
serial `wbm run` of the same scenes, byte for byte; the scene parser's own messages for bad axes.
Every Dask process a test starts is stopped by it, within bounded time.
"""
import cmath
import json
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import wbm
import wbm_study

pytest.importorskip("distributed")

CLI = os.environ["WBM_CLI"]
ROOT = Path(__file__).resolve().parents[2]
ROD = ROOT / "examples" / "scenes" / "rod_continuation.toml"
GAPS = [14.5e-3, 14.6e-3, 14.7e-3, 14.8e-3, 14.9e-3, 15.0e-3]


def rod_scene(folder):
    """The example's rod in harmonic balance with H = 15: its branch reaches the range end for every
    gap of GAPS (with M = 64 Fourier functions, the undamped top function cuts it at 1310 Hz for
    half of them)."""
    text = ROD.read_text()
    assert "dimension = 64" in text
    path = folder / "rod.toml"
    path.write_text(text.replace("dimension = 64", "harmonics = 15"))
    return path

# m ẍ + α m ẋ + k x = F cos ωt, far from its stop: |X| = F / |k − m ω² + i α m ω|.
OSCILLATOR = {"structure": {"mass": 1.0, "stiffness": 4e4}, "damping": {"alpha": 5.0},
              "forcing": {"amplitude": 5.0, "frequency_hz": [25.0, 40.0], "points": 31},
              "contact": {"law": "linear", "stiffness": 4e5, "gap": 1.0},
              "basis": {"trial": "fourier", "dimension": 16}}


def receptance_amplitude(force, frequency_hz):
    w = 2 * math.pi * frequency_hz
    return force / abs(4e4 - w * w + 1j * 5.0 * w)


def test_a_linear_study_gives_the_closed_form_peak(tmp_path):
    study = {"scene": OSCILLATOR, "collect": ["peak_amplitude", "peak_frequency", "points", "folds"],
             "axis": [{"key": "forcing.amplitude", "values": [1.0, 2.0, 4.0], "unit": "N"}]}
    table = wbm.study(study, output=tmp_path / "s", workers=2)
    assert list(table.columns) == ["case", "forcing.amplitude [N]", "status", "peak_amplitude_dof0 [m]",
                                   "peak_frequency_dof0 [Hz]", "points [-]", "folds [-]", "message"]
    assert list(table["status"]) == ["converged"] * 3
    for force, peak, f in zip(table["forcing.amplitude [N]"], table["peak_amplitude_dof0 [m]"],
                              table["peak_frequency_dof0 [Hz]"]):
        # (max u − min u)/2 over P = 1024 samples of a cosine: within cos(π/P) of its amplitude.
        exact = receptance_amplitude(force, f)
        assert exact * math.cos(math.pi / 1024) * (1 - 1e-12) <= peak <= exact * (1 + 1e-12)
    assert set(table["points [-]"]) == {31.0}
    assert table["folds [-]"].isna().all()  # a sweep writes no folds.csv: an empty cell
    csv = (tmp_path / "s" / "study.csv").read_text().splitlines()
    assert csv[0].startswith("case,forcing.amplitude [N],status,")
    assert csv[1].split(",")[6] == ""
    assert (tmp_path / "s" / "study.png").stat().st_size > 0


def test_a_case_past_its_time_limit_is_a_row_with_the_key_to_raise(tmp_path):
    study = {"scene": str(rod_scene(tmp_path)), "collect": ["folds"], "case_timeout_s": 0.05,
             "axis": [{"key": "contact.gap", "values": [14.5e-3]}]}
    table = wbm.study(study, output=tmp_path / "s", workers=1)
    assert list(table["status"]) == ["killed by signal 9"]
    assert "raise case_timeout_s" in table["message"][0] and table["folds [-]"].isna().all()
    assert not (tmp_path / "s" / "cases").exists() or not any((tmp_path / "s" / "cases").iterdir())
    study["case_timeout_s"] = 0  # no folder was written: raising the limit runs the case again
    assert list(wbm.study(study, output=tmp_path / "s", workers=1)["status"]) == ["converged"]


def test_keys_reach_every_table_of_an_array_or_one_entry():
    base = {"contact": [{"gap": 1.0}, {"gap": 2.0}], "forcing": {"amplitude": 1.0}}
    assert wbm_study.scene_with(base, [("contact.gap", 3.0)])["contact"] == [{"gap": 3.0}, {"gap": 3.0}]
    assert wbm_study.scene_with(base, [("contact[1].gap", 3.0)])["contact"] == [{"gap": 1.0}, {"gap": 3.0}]
    assert wbm_study.scene_with({"contact": {"gap": 1.0}}, [("contact[0].gap", 2.0)]) == {"contact": {"gap": 2.0}}
    with pytest.raises(wbm_study.StudyError, match=r"has 2 contact table\(s\), so \[2\] does not exist"):
        wbm_study.scene_with(base, [("contact[2].gap", 3.0)])
    with pytest.raises(wbm_study.StudyError, match="is not a key name"):
        wbm_study.parse_key("contact.gap-1")


def test_ranges_and_draws_follow_their_definitions():
    kind, log = wbm_study.axis_values({"range": {"from": 1e-4, "to": 1e-1, "points": 4, "spacing": "log"}}, "a")
    assert [math.log10(v) for v in log] == pytest.approx([-4, -3, -2, -1], abs=1e-12)
    spec = {"distribution": "lognormal", "median": 2e-3, "sigma": 0.1, "samples": 20001, "seed": 7}
    _, draws = wbm_study.axis_values({"random": spec}, "a")
    assert sorted(draws)[10000] == pytest.approx(2e-3, rel=0.01)  # the median of median·exp(σz)
    logs = [math.log(v / 2e-3) for v in draws]
    assert math.sqrt(sum(x * x for x in logs) / len(logs)) == pytest.approx(0.1, rel=0.02)
    assert wbm_study.axis_values({"random": spec}, "a")[1] == draws  # the seed fixes the draws


@pytest.mark.parametrize("axis, message", [
    ({"key": "contact.gapp", "values": [1e-3]}, r"case 0 \(contact.gapp = 0.001\): <study>: contact.gapp: unknown key; allowed here"),
    ({"key": "basis.dimension", "values": [16, -3]}, r"case 1 \(basis.dimension = -3\): .*basis.dimension"),
    ({"key": "contact.gap", "range": {"from": 0.0, "to": 1.0, "points": 3, "spacing": "log"}}, r"spacing = \"log\" needs from > 0"),
    ({"key": "contact.gap", "random": {"distribution": "normal", "mean": 1.0, "samples": 3}}, r"random.std = None: expected a finite number"),
])
def test_a_bad_axis_is_refused_before_any_case_runs(tmp_path, axis, message):
    out = tmp_path / "never"
    with pytest.raises(ValueError, match=message):
        wbm.study({"scene": OSCILLATOR, "axis": [axis]}, output=out, workers=1)
    assert not out.exists()


def test_the_command_refuses_a_bad_study_and_writes_nothing(tmp_path):
    (tmp_path / "s.toml").write_text(f'scene = "{ROD}"\ncombine = "zip"\n'
                                     '[[axis]]\nkey = "contact.gap"\nvalues = [1e-3, 2e-3]\n'
                                     '[[axis]]\nkey = "forcing.amplitude"\nvalues = [1.0]\n')
    p = subprocess.run([CLI, "study", str(tmp_path / "s.toml"), "-o", str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2
    assert "combine = \"zip\" needs axes of one length (got contact.gap: 2, forcing.amplitude: 1)" in p.stderr
    assert not (tmp_path / "out").exists()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop(processes):
    for p in processes:
        if p.poll() is None:
            p.terminate()
    for p in processes:
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(timeout=10)


def wait_for(condition, seconds, what):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {seconds} s waiting for {what}")


def same_as_serial_runs(folder, tmp_path):
    """Every case folder's CSV files equal, byte for byte, those of `wbm run` of its scene.json."""
    cases = sorted(p for p in (folder / "cases").iterdir() if p.is_dir())
    for case in cases:
        out = tmp_path / "serial" / case.name
        subprocess.run([CLI, "run", str(case / "scene.json"), "-o", str(out), "-q", "--no-plots"], timeout=120)
        csvs = sorted(p.name for p in out.glob("*.csv"))
        assert csvs and csvs == sorted(p.name for p in case.glob("*.csv"))
        for name in csvs:
            assert (case / name).read_bytes() == (out / name).read_bytes(), f"{case.name}/{name}"
    return len(cases)


def test_a_scheduler_and_two_workers_finish_a_study_when_one_worker_is_killed(tmp_path):
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # workers need no wbm module
    logs = open(tmp_path / "dask.log", "w")
    procs = [subprocess.Popen(["dask-scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              stdout=logs, stderr=logs, env=env)]
    try:
        for _ in range(2):
            procs.append(subprocess.Popen(["dask-worker", address, "--nthreads", "1", "--no-nanny",
                                           "--no-dashboard", "--host", "127.0.0.1"],
                                          stdout=logs, stderr=logs, env=env))
        from distributed import Client
        with Client(address, timeout="30s") as c:
            c.wait_for_workers(2, timeout=30)
        folder = tmp_path / "study"
        killed = {}

        def kill_one_worker():  # once the first case is back, both workers are busy
            wait_for(lambda: (folder / "cases").is_dir() and any((folder / "cases").iterdir()), 60, "a case")
            killed["done_before"] = sum(1 for p in (folder / "cases").iterdir() if not p.name.startswith("."))
            procs[1].send_signal(signal.SIGKILL)
            procs[1].wait(timeout=10)

        killer = threading.Thread(target=kill_one_worker)
        killer.start()
        study = {"scene": str(rod_scene(tmp_path)), "collect": ["peak_frequency", "folds"],
                 "axis": [{"key": "contact.gap", "values": GAPS}]}
        table = wbm.study(study, output=folder, scheduler=address)
        killer.join(timeout=60)
        assert procs[1].returncode == -signal.SIGKILL and killed["done_before"] < 6
        assert list(table["status"]) == ["converged"] * 6
        assert (table["folds [-]"] == 2.0).all()
        assert same_as_serial_runs(folder, tmp_path) == 6
    finally:
        stop(procs[::-1])
        logs.close()


def test_an_interrupted_study_resumes_without_recomputing(tmp_path):
    (tmp_path / "s.toml").write_text(f'scene = "{rod_scene(tmp_path)}"\ncollect = ["peak_amplitude"]\n'
                                     '[[axis]]\nkey = "contact.gap"\n'
                                     'range = { from = 14.5e-3, to = 15.0e-3, points = 6 }\n')
    folder = tmp_path / "out"
    command = [CLI, "study", str(tmp_path / "s.toml"), "-o", str(folder), "--workers", "1"]
    first = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        done = lambda: [p for p in (folder / "cases").glob("*/case.json")] if (folder / "cases").is_dir() else []
        wait_for(lambda: len(done()) >= 2, 120, "two cases")
        first.send_signal(signal.SIGINT)
        _, err = first.communicate(timeout=60)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 130, err
    assert "interrupted; the finished cases are kept" in err
    kept = {p.parent.name: p.stat().st_mtime_ns for p in done()}
    assert 2 <= len(kept) < 6 and not (folder / "study.csv").exists()
    again = subprocess.run(command + ["-q"], capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    summary = json.loads((folder / "study.json").read_text())
    assert summary["resumed"] == len(kept) and summary["run"] == 6 - len(kept)
    assert {n: (folder / "cases" / n / "case.json").stat().st_mtime_ns for n in kept} == kept
    assert len((folder / "study.csv").read_text().splitlines()) == 7
