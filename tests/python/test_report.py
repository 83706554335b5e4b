"""reproduce/report.py (issue #41, item 4): REPORT.md opens with the claims of every section,
counted from the sections' own lines: the lists that claims_markdown writes (one line per Claim,
closed by "a agree, d disagree, n not checked.") and the sentences still written by hand that
start "Claim". Crafted fragments, counted by hand here.
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
The word agrees outside a claim sentence is not a verdict.
"""


def test_the_summary_counts_every_section_and_lists_what_does_not_agree():
    report = load_report_module()
    summary = report.claims_summary([("fig_x", FIG), ("no_claims", "## Text\n\nNothing checked.\n"), ("blade", BLADE)])
    assert "| fig_x | 2 | 1 | 1 | 0 | 0 |" in summary
    assert "| blade | 0 | 0 | 0 | 1 | 1 |" in summary
    assert "no_claims" not in summary
    assert "| all | 2 | 1 | 1 | 1 | 1 |" in summary
    assert '- fig_x, disagrees: "Haar is best (a: b)"' in summary
    assert '- fig_x, not checked: "the plateaus coincide"' in summary
    assert "the error decreases" not in summary  # agreeing claims are only counted


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
    assert "| all | 2 | 1 | 1 | 0 | 0 |" in text  # the failed blade's fragment is not counted
    assert "## Failed" in text
