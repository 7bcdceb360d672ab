"""`analyse --out DIR` and `accuracy --out DIR` replace only their own earlier output: a non-empty
directory without their marker file (analysis.json / accuracy.json with their format tag, or an
untagged accuracy.json with its keys) is refused."""
import json

from conftest import SOURCE_DIR

TABLES = SOURCE_DIR / "data" / "reference" / "quick" / "tables"


def test_analyse_refuses_a_users_nonempty_directory_and_leaves_it_alone(run_budjam, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "runs.csv").write_text("my own data\n")
    r = run_budjam("analyse", "--tables", TABLES, "--out", out, check=False)
    assert r.returncode == 2
    assert len(r.stderr.splitlines()) == 1 and str(out) in r.stderr and "analysis.json" in r.stderr
    assert [p.name for p in out.iterdir()] == ["runs.csv"]
    assert (out / "runs.csv").read_text() == "my own data\n"


def test_analyse_refuses_a_foreign_analysis_json(run_budjam, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "analysis.json").write_text(json.dumps({"format": "something-else", "groups": []}))
    r = run_budjam("analyse", "--tables", TABLES, "--out", out, check=False)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "something-else" in (out / "analysis.json").read_text()


def test_analyse_replaces_its_own_earlier_output(run_budjam, tmp_path):
    out = tmp_path / "analysis"
    run_budjam("analyse", "--tables", TABLES, "--out", out)
    first = json.loads((out / "analysis.json").read_text())
    assert first["format"] == "budjam-analysis"
    r = run_budjam("analyse", "--tables", TABLES, "--out", out, check=False)
    assert r.returncode == 0, r.stderr
    assert (out / "runs.csv").exists()


def test_accuracy_refuses_a_users_nonempty_directory_and_leaves_it_alone(run_budjam, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "accuracy.md").write_text("my notes\n")
    (tmp_path / "packs").mkdir(exist_ok=True)
    r = run_budjam("accuracy", "--packings", f"q={tmp_path / 'packs'}", "--out", out, check=False)
    assert r.returncode == 2
    assert len(r.stderr.splitlines()) == 1 and str(out) in r.stderr and "accuracy.json" in r.stderr
    assert (out / "accuracy.md").read_text() == "my notes\n"


def test_accuracy_accepts_its_own_earlier_output(run_budjam, tmp_path):
    out = tmp_path / "acc"
    out.mkdir()
    (out / "accuracy.md").write_text("old\n")
    (out / "accuracy.json").write_text(json.dumps({"front_rule": {}, "rows": [], "defaults_on_front": True}))
    (tmp_path / "packs").mkdir(exist_ok=True)
    r = run_budjam("accuracy", "--packings", f"q={tmp_path / 'packs'}", "--out", out, check=False)
    # past the --out check: whatever follows, it is not the refusal of a foreign directory
    assert "is not empty" not in r.stderr


def test_accuracy_refuses_a_json_of_another_format(run_budjam, tmp_path):
    out = tmp_path / "other"
    out.mkdir()
    foreign = json.dumps({"format": "my-sweep", "version": 1, "front_rule": {}, "rows": [], "defaults_on_front": True})
    (out / "accuracy.json").write_text(foreign)
    (tmp_path / "packs").mkdir(exist_ok=True)
    r = run_budjam("accuracy", "--packings", f"q={tmp_path / 'packs'}", "--out", out, check=False)
    assert r.returncode == 2 and "is not empty" in r.stderr
    assert (out / "accuracy.json").read_text() == foreign


def test_accuracy_accepts_its_own_tagged_output(run_budjam, tmp_path):
    out = tmp_path / "tagged"
    out.mkdir()
    (out / "accuracy.json").write_text(json.dumps({"format": "budjam-accuracy", "version": 1}))
    (tmp_path / "packs").mkdir(exist_ok=True)
    r = run_budjam("accuracy", "--packings", f"q={tmp_path / 'packs'}", "--out", out, check=False)
    assert "is not empty" not in r.stderr
