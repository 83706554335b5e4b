"""reproduce/report.py (issue #41, item 4): REPORT.md opens with the claims of every section,
counted from the sections' own lines: the lists that claims_markdown writes (one line per Claim,
closed by "a agree, d disagree, n not checked."). A verdict typed into a sentence is not counted but
listed, so that it shows. Crafted fragments, counted by hand here.
"""
import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "reproduce" / "report.py"


def load_report_module():
    spec = importlib.util.spec_from_file_location("report", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# The format of claims_markdown (reproduce/common/combinations.cpp), two lists in one section.
FIG = """## Fig. X

Against the paper's text:

- "the error decreases": 1e-3 → 1e-5: agrees.
- "Haar is best (a: b)": error 0.3 against 0.1: disagrees.
- "the plateaus coincide": no reference: not checked.

1 agree, 1 disagree, 1 not checked.

Against the paper's text:

- "the peak is at 1300 Hz": 1300.07 Hz: agrees.

1 agree, 0 disagree, 0 not checked.
"""

BLADE = """## Blade

Claim: the frequencies agree to 1e-6: **agrees** (3.1e-07). Claim (Sec. 5.2): both edges touch: **disagrees** (one).
The two frequencies agree; "agree" is not a verdict word.
"""


def test_the_summary_counts_every_section_and_lists_what_does_not_agree():
    report = load_report_module()
    summary = report.claims_summary([("fig_x", FIG), ("no_claims", "## Text\n\nNothing checked.\n"), ("blade", BLADE)])
    assert "| fig_x | 2 | 1 | 1 |" in summary
    assert "| blade |" not in summary  # its verdicts are typed, not claims: listed below, not counted
    assert "no_claims" not in summary
    assert "| all | 2 | 1 | 1 |" in summary
    assert '- fig_x, disagrees: "Haar is best (a: b)"' in summary
    assert '- fig_x, not checked: "the plateaus coincide"' in summary
    assert "the error decreases" not in summary  # agreeing claims are only counted
    typed = summary[summary.index("Verdicts not through `Claim`"):]
    assert typed.count("- blade: ") == 1 and "**disagrees**" in typed  # one line, both verdicts on it
    assert "is not a verdict word" not in summary


def test_claims_alone_leave_no_list_of_typed_verdicts():
    report = load_report_module()
    assert "Verdicts not through" not in report.claims_summary([("fig_x", FIG)])


def test_report_md_opens_with_the_summary_and_leaves_failed_sections_out(tmp_path):
    report = load_report_module()
    for fid, text in [("jl14_fig06", FIG), ("ll11_blade", BLADE)]:
        (tmp_path / fid).mkdir()
        (tmp_path / fid / "report.md").write_text(text)
    (tmp_path / ".runs").mkdir()
    (tmp_path / ".runs" / "ll11_blade.json").write_text(
        json.dumps({"executable": "ll11_blade", "exit_code": 2, "message": "stopped", "seconds": 1.0}))
    import sys
    argv = sys.argv
    sys.argv = ["report.py", str(tmp_path)]
    try:
        report.main()
    except SystemExit as e:
        assert e.code == 1  # a failed run fails the report after writing it
    finally:
        sys.argv = argv
    text = (tmp_path / "REPORT.md").read_text()
    assert text.index("## Claims against the papers") < text.index("## Fig. X")
    assert "| all | 2 | 1 | 1 |" in text
    assert "- ll11_blade: " not in text  # the failed blade's fragment is left out
    assert "## Failed" in text


def test_reproductions_list_matches_the_sources():
    """reproductions.txt is the one list (issue #41, item 4): every executable it names has its
    source reproduce/<executable>.cpp writing the section id of the list (the id its
    reproduce::Run::from_args call gives), every source with a main is listed once, and every figure
    function it names is a function of plot.py (or of plot_friction.py or plot_impacts.py, which it
    imports)."""
    import re

    report = load_report_module()
    rows = report.reproductions()
    root = SCRIPT.parent
    listed = [exe for exe, _, _ in rows]
    assert len(listed) == len(set(listed)), "an executable is listed twice"
    for exe, fid, figure in rows:
        source = (root / f"{exe}.cpp").read_text()
        ids = re.findall(r'from_args\(argc, argv, "([a-z0-9_]+)"\)', source)
        assert ids == [fid], f"{exe}.cpp writes {ids}, reproductions.txt says {fid}"
        if figure is not None:
            modules = "".join((root / m).read_text() for m in ("plot.py", "plot_friction.py", "plot_impacts.py"))
            assert re.search(rf"^def {figure}\(folder\)", modules, re.M), figure
    with_main = {p.stem for p in root.glob("*.cpp") if "int main(" in p.read_text()}
    assert with_main - {"bench_scaling"} == set(listed), with_main ^ set(listed)
    assert report.report_id("jl14_extremes_penalty") == "jl14_extremes"
    assert report.report_id("not_listed") == "not_listed"
