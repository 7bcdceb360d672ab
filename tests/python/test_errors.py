"""The Python module's error taxonomy: bad input raises budjam.InputError naming the file (and key),
never a JSONDecodeError, a pandas ParserError, a UnicodeDecodeError or a RuntimeError; a quantity the
input does not have raises budjam.NoResultError; messages are one line with control bytes escaped,
as the command line prints them."""
import json
import os

import pytest

import budjam
from conftest import PACKING

SUMMARY = {"format": "budjam-summary", "version": 1, "status": "finished", "seed": 1, "L": 8, "P0": None,
           "phi_J": 0.84, "targets": [], "unjammings": []}


def make_run(directory, summary=None, steps="step,phi\n0,0.5\n"):
    directory.mkdir()
    (directory / "packings").mkdir()
    (directory / "summary.json").write_bytes(summary if isinstance(summary, bytes) else
                                             json.dumps(SUMMARY if summary is None else summary).encode())
    (directory / "steps.csv").write_bytes(steps if isinstance(steps, bytes) else steps.encode())
    (directory / "divisions.csv").write_text("step,phi\n")
    return directory


def test_a_well_formed_run_loads(tmp_path):
    run = budjam.load_run(make_run(tmp_path / "run"))
    assert run.summary["phi_J"] == 0.84 and list(run.steps["phi"]) == [0.5]


@pytest.mark.parametrize("content, message", [
    (b'{"format": "budjam-summary", ', "summary.json: invalid JSON"),
    (b'{"format": "budjam-summary", "s": "\xff\xfe"}', "summary.json: invalid JSON"),
    (b"[1, 2, 3]", "summary.json: not a budjam run summary"),
])
def test_load_run_refuses_a_bad_summary_with_input_error_naming_the_file(tmp_path, content, message):
    with pytest.raises(budjam.InputError, match=message) as e:
        budjam.load_run(make_run(tmp_path / "run", summary=content))
    assert type(e.value) is budjam.InputError


@pytest.mark.parametrize("steps", [b"step,phi\n1,2,3,4\n\"unterminated\n", b"step,phi\n\xff\xfe,1\n"])
def test_load_run_refuses_a_bad_table_with_input_error_naming_the_file(tmp_path, steps):
    with pytest.raises(budjam.InputError, match="steps.csv"):
        budjam.load_run(make_run(tmp_path / "run", steps=steps))


def test_load_run_refuses_packings_that_are_a_plain_file(tmp_path):
    run = make_run(tmp_path / "run")
    (run / "packings").rmdir()
    (run / "packings").write_text("a file\n")
    with pytest.raises(budjam.InputError, match="packings: not a directory"):
        budjam.load_run(run)
    with pytest.raises(budjam.InputError, match="packings: not a directory"):
        budjam.survival([run])


def test_survival_on_a_summary_that_is_a_json_array_raises_input_error_naming_the_file(tmp_path):
    with pytest.raises(budjam.InputError, match="summary.json: not a budjam run summary"):
        budjam.survival([make_run(tmp_path / "run", summary=[1, 2])])


def test_survival_of_runs_of_two_feedback_strengths_raises_input_error_naming_the_key(tmp_path):
    runs = []
    for seed, p0 in ((1, "1e-3"), (2, "1e-1")):
        run = make_run(tmp_path / f"run{seed}", summary=dict(SUMMARY, seed=seed))
        (run / "scene.toml").write_text(f"[run]\nseed = {seed}\n[growth]\nP0 = {p0}\n")
        runs.append(run)
    with pytest.raises(budjam.InputError, match=r"run2/scene.toml: growth\.P0 = 0\.1, but .*give them to survival apart"):
        budjam.survival(runs)


def test_messages_escape_control_bytes_and_stay_on_one_line(tmp_path):
    with pytest.raises(budjam.InputError) as e:
        budjam.load_run(make_run(tmp_path / "run\x1b[2J\x07", summary=b'{"a": '))
    assert "run\\x1b[2J\\x07/summary.json: invalid JSON" in str(e.value)
    (tmp_path / "esc.pack").write_bytes(PACKING.read_bytes().replace(b"shear 0\n", b"shear 0\nmeta k\x1b[2J\r x\n"))
    with pytest.raises(budjam.InputError) as e:
        budjam.read_packing(tmp_path / "esc.pack")
    assert "\\x1b[2J\\x0d" in str(e.value)
    assert not any(ord(c) < 0x20 for c in str(e.value))


def test_moduli_of_an_unjammed_packing_raises_no_result_error():
    gas = budjam.Packing(L=8.0, x=[2.0, 5.0], y=[2.0, 5.0], theta=[0.0, 1.0], b=[0.5, 0.7])
    with pytest.raises(budjam.NoResultError, match="is not jammed: all 2 cells are rattlers"):
        budjam.moduli(gas)


def test_a_packing_with_coincident_cells_is_refused_by_input_error():
    with pytest.raises(budjam.InputError, match="the mother of cell 0 and the mother of cell 1 are r = 0 apart"):
        budjam.Packing(L=8.0, x=[2.0, 2.0], y=[2.0, 2.0], theta=[0.0, 0.0], b=[0.5, 0.5])


def test_arrays_of_unequal_length_and_an_unknown_export_format_raise_input_error(tmp_path):
    with pytest.raises(budjam.InputError, match="y: expected a 1-d array of length 1"):
        budjam.Packing(L=8.0, x=[0.1], y=[0.1, 0.2], theta=[0.0], b=[0.5])
    with pytest.raises(budjam.InputError, match="format: must be one of"):
        budjam.export(budjam.read_packing(PACKING), str(tmp_path / "x.pdb"), "pdb")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("name", ["sub/", "", ".", "d", "x" * 250])
@pytest.mark.parametrize("write", [lambda p, path: p.write(path),
                                   lambda p, path: budjam.export(p, path, "xyz"),
                                   lambda p, path: budjam.export(p, path, "gsd")], ids=["write", "xyz", "gsd"])
def test_an_output_path_that_names_no_file_raises_input_error_and_writes_nothing(tmp_path, write, name):
    packing = budjam.read_packing(PACKING)
    (tmp_path / "sub").mkdir()
    (tmp_path / "d").mkdir()
    path = "" if name == "" else f"{tmp_path}/{name}"
    with pytest.raises(budjam.InputError):
        write(packing, path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "sub"]
    assert not any((tmp_path / "sub").iterdir()) and not any((tmp_path / "d").iterdir())


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_reading_a_fifo_or_a_device_raises_input_error_at_once(tmp_path, kind):
    path = tmp_path / "p.pack"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path = "/dev/zero"
    with pytest.raises(budjam.InputError, match="not a regular file"):
        budjam.read_packing(path)


@pytest.mark.parametrize("name", ["summary.json", "scene.toml", "notes.xyz", "packings/target_0.pack",
                                  "packings/jammed.pack", "packings/../steps.csv"])
@pytest.mark.parametrize("write", [lambda p, path: p.write(path),
                                   lambda p, path: budjam.export(p, path, "xyz")], ids=["write", "xyz"])
def test_the_python_writers_refuse_a_runs_own_files_as_the_command_line_does(tmp_path, write, name):
    """Packing.write and budjam.export apply the command line's output-name rules (one check): nothing at a
    run directory's top level, and no run packing, which only grow writes; the run is byte-identical after."""
    run = make_run(tmp_path / "run")
    (run / ".budjam-run").write_text("budjam-run 1\n")
    (run / "scene.toml").write_text("[run]\n")
    (run / "packings" / "target_0.pack").write_bytes(PACKING.read_bytes())
    (run / "packings" / "jammed.pack").write_bytes(PACKING.read_bytes())
    before = {p: p.read_bytes() for p in run.rglob("*") if p.is_file()}
    with pytest.raises(budjam.InputError, match="budjam run") as e:
        write(budjam.read_packing(PACKING), str(run / name))
    assert "\n" not in str(e.value)
    assert {p: p.read_bytes() for p in run.rglob("*") if p.is_file()} == before
    # Beside the packings, under a name of its own, the same writers write.
    write(budjam.read_packing(PACKING), str(run / "packings" / "mine.out"))
    assert (run / "packings" / "mine.out").is_file()
