"""One name per quantity between the command line and Python: for each result (moduli, dos,
rigidity, survival, a run's summary and tables) the Python result has the keys of the command's
JSON with equal values and, under "table", the columns of its CSV with equal values. The keys only
Python has are the documented ones, and none of them is a name the command's JSON or CSV uses."""
import json

import numpy as np
import pandas
import pytest

import budjam
from conftest import SOURCE_DIR

# Keys of the Python results that the command line has no counterpart for (arrays it does not write).
PYTHON_ONLY = {
    "moduli": set(),
    "dos": {"cells", "eigenvectors", "mass"},
    "rigidity": {"lobe_cluster", "bar_lobes", "cluster_cells", "cluster_joints", "largest_cluster"},
    "survival": set(),
}


def cli_files(run_budjam, tmp_path, command, *args):
    """`budjam COMMAND ARGS --out BASE`: its JSON (without the input's name) and its CSV table, or None."""
    base = tmp_path / command
    run_budjam(command, *args, "--out", base, "--quiet")
    document = json.loads(base.with_suffix(".json").read_text())
    document.pop("file", None)
    csv = base.with_suffix(".csv")
    return document, pandas.read_csv(csv, float_precision="round_trip") if csv.exists() else None


def assert_named_alike(result, kind, document, table):
    extras = PYTHON_ONLY[kind]
    assert set(result) - {"table"} - extras == set(document), kind
    assert extras <= set(result), kind
    assert not extras & (set(document) | set(table.columns if table is not None else ())), kind
    for key, value in document.items():
        assert result[key] == value, f"{kind}: {key}"
    if table is None:
        assert "table" not in result, kind
        return
    assert list(result["table"]) == list(table.columns), kind
    for column in table.columns:
        np.testing.assert_array_equal(result["table"][column], table[column].to_numpy(), err_msg=f"{kind}: {column}")


def test_moduli_is_named_as_budjam_moduli(run_budjam, relaxed, tmp_path):
    assert_named_alike(budjam.moduli(relaxed), "moduli", *cli_files(run_budjam, tmp_path, "moduli", relaxed))


def test_spectrum_is_named_as_budjam_dos(run_budjam, relaxed, tmp_path):
    assert_named_alike(budjam.spectrum(relaxed), "dos", *cli_files(run_budjam, tmp_path, "dos", relaxed))


@pytest.mark.parametrize("network", ["load-bearing", "raw"])
def test_rigidity_is_named_as_budjam_rigidity(run_budjam, relaxed, tmp_path, network):
    document, table = cli_files(run_budjam, tmp_path, "rigidity", relaxed, "--network", network)
    assert_named_alike(budjam.rigidity(relaxed, network), "rigidity", document, table)


def test_survival_is_named_as_budjam_survival(run_budjam, run_dir, tmp_path):
    document, table = cli_files(run_budjam, tmp_path, "survival", run_dir)
    assert_named_alike(budjam.survival([run_dir]), "survival", document, table)
    # A run given twice is one sample in both.
    document, table = cli_files(run_budjam, tmp_path, "survival", run_dir, run_dir)
    assert document["duplicates"]
    assert_named_alike(budjam.survival([run_dir, run_dir]), "survival", document, table)


def test_a_runs_summary_and_tables_are_named_as_its_files(run_dir):
    run = budjam.load_run(run_dir)
    assert run.summary == json.loads((run_dir / "summary.json").read_text())
    for name, frame in run.tables.items():
        table = pandas.read_csv(run_dir / f"{name}.csv", float_precision="round_trip")
        assert list(frame.columns) == list(table.columns), name
        for column in table.columns:
            np.testing.assert_array_equal(frame[column].to_numpy(), table[column].to_numpy(), err_msg=f"{name}: {column}")


def test_growth_events_are_named_as_the_runs_summary(run_dir):
    """The events of budjam.grow carry what summary.json records under its names, with its values."""
    summary = json.loads((run_dir / "summary.json").read_text())
    events = list(budjam.grow(SOURCE_DIR / "data" / "scenes" / "demo.toml"))
    jammed = [e for e in events if e["kind"] == "jammed"][-1]
    for key in ("phi_J", "Z_J", "Z_iso_J", "dZ_J", "N_nr_J", "u_J", "tagged_J"):
        assert jammed[key] == summary[key], key
    assert jammed["episode"] == summary["jamming_episode"]
    unjammed = [e for e in events if e["kind"] == "unjammed"]
    assert [{k: e[k] for k in ("episode", "phi_J", "targets_lost")} for e in unjammed] == \
        [{k: u[k] for k in ("episode", "phi_J", "targets_lost")} for u in summary["unjammings"]]
    lost = sum(u["targets_lost"] for u in summary["unjammings"])
    targets = [e for e in events if e["kind"] == "target"][lost:]
    assert len(targets) == len(summary["targets"]) > 0
    for event, target in zip(targets, summary["targets"]):
        for key in ("index", "dphi", "Z", "dZ", "N_nr", "chi_c"):
            assert event[key] == target[key], key
    if summary["phi_2"] is not None:
        last = [e for e in events if e["kind"] == "phi2"][-1]
        assert (last["phi_2"], last["Z_2"], last["dZ_2"]) == (summary["phi_2"], summary["Z_2"], summary["dZ_2"])


def test_docs_python_lists_the_table_columns_each_analysis_returns(relaxed, run_dir):
    """The "table" column of the analyses table of docs/python.md names exactly the columns the result has."""
    import re
    page = (SOURCE_DIR / "docs" / "python.md").read_text()
    results = {"moduli": budjam.moduli(relaxed), "rigidity": budjam.rigidity(relaxed),
               "spectrum": budjam.spectrum(relaxed), "survival": budjam.survival([run_dir])}
    for name, result in results.items():
        row = next(line for line in page.splitlines() if line.startswith(f"| `{name}("))
        listed = re.findall(r"`([A-Za-z_]+)`", row.split(" | ")[2])
        assert listed == list(result.get("table", {})), name
