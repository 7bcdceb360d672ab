"""A preset's report reads the committed jamming ensembles as this build analyses them (their
reanalysed analysis.json), never the analysis.json stored beside their tables by the build that grew
them; a fresh PRESET=jamming analysis given as JAMMING_TABLES is read as it is."""
import subprocess

from conftest import SOURCE_DIR


def report_command(*assignments):
    r = subprocess.run(["make", "-s", "-n", "-f", "Makefile.analysis", "PRESET=quick", *assignments,
                        "analysis/quick/REPRODUCTION.md"], cwd=SOURCE_DIR, capture_output=True, text=True)
    return r.stdout.replace("\\\n", " ")


def test_the_committed_jamming_tables_are_read_reanalysed():
    line = next(l for l in report_command().splitlines() if "scripts/report.py" in l)
    assert "--jamming data/reference/jamming/reanalysed " in line


def test_a_fresh_jamming_analysis_is_read_as_it_is(tmp_path):
    (tmp_path / "analysis.json").write_text("{}")
    line = next(l for l in report_command(f"JAMMING_TABLES={tmp_path}").splitlines() if "scripts/report.py" in l)
    assert f"--jamming {tmp_path} " in line
