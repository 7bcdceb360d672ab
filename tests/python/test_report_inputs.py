"""A preset's report reads the committed jamming ensembles as this build analyses them (their
reanalysed analysis.json), never the analysis.json stored beside their tables by the build that grew
them; a fresh PRESET=jamming analysis given as JAMMING_TABLES is read as it is. The moduli and
spectra stages record a saddle (exit 1, its JSON written) and stop on any other failure."""
import subprocess

import pytest

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


@pytest.mark.parametrize("stage", ["moduli", "dos"])
@pytest.mark.parametrize("status,recorded", [(0, True), (1, True), (3, False)])
def test_a_sidecar_stage_records_a_saddle_and_stops_on_a_failure(tmp_path, stage, status, recorded):
    run = tmp_path / "run"
    (run / "packings").mkdir(parents=True)
    (run / "summary.json").write_text("{}\n")
    (run / "packings" / "jammed.pack").write_text("a packing\n")
    # budjam STAGE PACK --out BASE --quiet: writes BASE.json, then exits as a saddle (1) or a failure would
    fake = tmp_path / "budjam"
    fake.write_text(f'#!/bin/sh\necho "{{}}" > "$4.json"\nexit {status}\n')
    fake.chmod(0o755)
    r = subprocess.run(["make", "-s", "-f", "Makefile.analysis", "PRESET=quick", f"BUDJAM={fake}", f"{run}/{stage}.done"],
                       cwd=SOURCE_DIR, capture_output=True, text=True)
    assert (r.returncode == 0) == recorded, r.stderr
    assert (run / f"{stage}.done").exists() == recorded
    assert (run / "packings" / f"jammed.{stage}.json").exists()
