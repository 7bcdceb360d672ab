"""The Python module's error taxonomy: bad input raises budjam.InputError naming the file (and key),
never a JSONDecodeError, a pandas ParserError, a UnicodeDecodeError or a RuntimeError; a quantity the
input does not have raises budjam.NoResultError; messages are one line with control bytes escaped,
as the command line prints them."""
import json
import os
import signal

import pytest

import budjam
from conftest import PACKING

SUMMARY = {"format": "budjam-summary", "version": 1, "status": "finished", "seed": 1, "L": 8, "P0": None,
           "phi_J": 0.84, "N_nr_J": 30, "u_J": 0.1, "targets": [], "unjammings": []}
# The columns of steps.csv that the analyses read; the network columns are empty before jamming.
STEPS = "step,phi,P,N,N_f,N_u_buds,chi_c,tagged_active,divisions_since_jamming,Z,dZ\n0,0.5,0,2,,,,,,,\n"
BUD_EVENTS = "episode,cell_id,event,step,phi,a\n0,7,tagged,10,0.84,0\n0,7,completed,12,0.85,0.25\n"


def make_run(directory, summary=None, steps=STEPS):
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


def test_moduli_of_an_unjammed_packing_raises_no_result_error_naming_the_packing():
    gas = budjam.Packing(L=8.0, x=[2.0, 5.0], y=[2.0, 5.0], theta=[0.0, 1.0], b=[0.5, 0.7])
    with pytest.raises(budjam.NoResultError, match="^packing is not jammed: all 2 cells are rattlers"):
        budjam.moduli(gas)
    with pytest.raises(budjam.NoResultError, match="^packing is not jammed: all 2 cells are rattlers"):
        budjam.rigidity(gas)
    assert budjam.rigidity(gas, "raw")["floppy_modes"]["plane"] == 3


@pytest.mark.parametrize("call, message", [
    (lambda p: budjam.moduli(None), "moduli: packing: must be a budjam.Packing or the path of a packing file"),
    (lambda p: budjam.rigidity(42), "rigidity: packing: must be a budjam.Packing or the path"),
    (lambda p: budjam.read_packing(42), "read_packing: path: must be a path (str or os.PathLike), got int"),
    (lambda p: budjam.moduli(p, solver=1), "moduli: solver: must be text (str), got int"),
    (lambda p: budjam.spectrum(p, "auto", "a"), "spectrum: modes: must be an integer, got str"),
    (lambda p: budjam.survival(["x"], epsilon="x"), "survival: epsilon: must be a number or None, got str"),
    (lambda p: budjam.survival(3), "survival: runs: must be a list of path"),
    (lambda p: budjam.export(p, 3, "xyz"), "export: path: must be a path (str or os.PathLike), got int"),
    (lambda p: p.write(3), "Packing.write: path: must be a path (str or os.PathLike), got int"),
    (lambda p: budjam.Packing("a", [1], [1], [1], [1]), "Packing: L: must be a number, got str"),
    (lambda p: budjam.Packing(8.0, [1.0, "x"], [1.0, 2.0], [0.0, 0.0], [0.5, 0.5]),
     "Packing: x: must be an array of numbers, got list"),
    (lambda p: budjam.Packing(), "Packing: missing argument L"),
    (lambda p: budjam.Packing(8.0, [1.0], [1.0], [0.0], [0.5], colour=1), "Packing: no argument named colour"),
    (lambda p: budjam.load_run(3), "load_run: directory: must be a path (str or os.PathLike), got int"),
    (lambda p: budjam.grow(PACKING, set=3), "grow: set: must be a dict of scene keys"),
    (lambda p: budjam.grow(PACKING, set=[3]), "grow: set: must be a dict of scene keys, a \"section.key=value\" "
     "string or a list of them, got a list holding int"),
    (lambda p: budjam.grow(PACKING, callback=3), "grow: callback: must be callable (or None), got int"),
])
def test_an_argument_of_the_wrong_type_raises_a_one_line_type_error_naming_it(call, message):
    with pytest.raises(TypeError) as e:
        call(budjam.read_packing(PACKING))
    assert str(e.value).startswith(message), str(e.value)
    assert "\n" not in str(e.value)


def test_survival_takes_one_run_directory_by_its_path_as_the_command_line_does(tmp_path):
    run = make_run(tmp_path / "run")
    (run / "bud_events.csv").write_text(BUD_EVENTS)
    (run / "scene.toml").write_text("[run]\nseed = 1\n")
    one, listed = budjam.survival(run), budjam.survival([run])
    assert one["runs"] == 1 and one["a_eps"] == listed["a_eps"]
    assert list(one["table"]["S"]) == list(listed["table"]["S"])


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
                                  "packings/jammed.pack", "packings/../steps.csv", "newsub/x.pack",
                                  "newsub/deeper/x.xyz", "packings/../newsub/x.pack"])
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
    def entries():
        return {p: p.read_bytes() if p.is_file() else None for p in run.rglob("*")}

    before = entries()
    with pytest.raises(budjam.InputError, match="budjam run") as e:
        write(budjam.read_packing(PACKING), str(run / name))
    assert "\n" not in str(e.value)
    assert entries() == before  # no new directory either
    # Beside the packings, under a name of its own, the same writers write.
    write(budjam.read_packing(PACKING), str(run / "packings" / "mine.out"))
    assert (run / "packings" / "mine.out").is_file()


def test_survival_of_no_runs_raises_input_error_saying_so():
    with pytest.raises(budjam.InputError, match="^survival: no run directories given$"):
        budjam.survival([])


@pytest.mark.parametrize("a, problem", [("inf", "not a finite number"), ("nan", "not a finite number"),
                                        ("-0.5", "expected a number >= 0"), ("", "empty, expected a number >= 0")])
def test_load_run_and_survival_refuse_a_bud_size_out_of_range_naming_file_line_and_column(tmp_path, a, problem):
    run = make_run(tmp_path / "run")
    (run / "bud_events.csv").write_text(BUD_EVENTS.replace(",0.25\n", f",{a}\n"))
    for read in (budjam.load_run, lambda r: budjam.survival([r])):
        with pytest.raises(budjam.InputError, match=f"bud_events.csv:3: column a: {problem}") as e:
            read(run)
        assert type(e.value) is budjam.InputError


@pytest.mark.parametrize("change, message", [
    ({"N_nr_J": -5}, r"N_nr_J: expected a non-negative integer or null \(got -5\)"),
    ({"version": 2}, r"version: 2 is not a summary format this budjam reads"),
    ({"phi_J": "0.84"}, r"phi_J: expected a number > 0 or null"),
    ({"tagged_J": "6"}, r"tagged_J: expected a non-negative integer"),
    ({"status": 3}, r"status: expected a string"),
    ({"targets": {}}, r"targets: not a list"),
    ({"targets": [{"dphi": "x"}]}, r"targets\[0\]\.dphi: expected a number > 0"),
])
def test_load_run_and_survival_check_summary_json_as_analyse_does(tmp_path, change, message):
    run = make_run(tmp_path / "run", summary=dict(SUMMARY, **change))
    (run / "bud_events.csv").write_text(BUD_EVENTS)
    for read in (budjam.load_run, lambda r: budjam.survival([r])):
        with pytest.raises(budjam.InputError, match="summary.json: " + message) as e:
            read(run)
        assert type(e.value) is budjam.InputError


def test_load_run_and_survival_name_the_file_of_a_number_overflow_and_a_missing_column(tmp_path):
    text = json.dumps(SUMMARY).replace('"N_nr_J": 30', '"N_nr_J": 1e999')
    overflow = make_run(tmp_path / "overflow", summary=text.encode())
    column = make_run(tmp_path / "column", steps=STEPS.replace(",dZ\n", "\n", 1).replace(",,\n", ",\n"))
    for run, message in ((overflow, "overflow/summary.json: invalid JSON: number overflow"),
                         (column, "column/steps.csv: no column 'dZ'")):
        (run / "bud_events.csv").write_text(BUD_EVENTS)
        for read in (budjam.load_run, lambda r: budjam.survival([r])):
            with pytest.raises(budjam.InputError, match=message) as e:
                read(run)
            assert type(e.value) is budjam.InputError


NAN = float("nan")


@pytest.mark.parametrize("arguments, message", [
    (dict(L=0.0), r"^L: must be finite and > 0 \(got 0\)$"),
    (dict(L=-8.0), r"^L: must be finite and > 0 \(got -8\)$"),
    (dict(L=NAN), r"^L: must be finite and > 0 \(got nan\)$"),
    (dict(x=[NAN]), r"^x\[0\]: not finite \(got nan\)$"),
    (dict(b=[-0.5]), r"^b\[0\]: must be >= 0 \(got -0.5\)$"),
    (dict(gamma0=[NAN]), r"^gamma0\[0\]: not finite \(got nan\)$"),
    (dict(shear=NAN), r"^shear: must be finite \(got nan\)$"),
    (dict(meta={"a b": 1}), r'^meta key "a b": letters, digits, _ \. - only$'),
    (dict(meta={"a": "x\ny"}), r'^meta\["a"\]: the value must be one line'),
    (dict(L=1e39), r"box side L = 1e\+39 must be at most 10000"),
])
def test_packing_constructor_refuses_what_a_file_cannot_hold_with_input_error_naming_the_argument(arguments, message):
    values = dict(dict(L=8.0, x=[2.0], y=[2.0], theta=[0.0], b=[0.5]), **arguments)
    with pytest.raises(budjam.InputError, match=message) as e:
        budjam.Packing(**values)
    assert type(e.value) is budjam.InputError
    assert "format_packing" not in str(e.value)


def test_a_packing_whose_meta_value_is_not_utf8_raises_input_error_naming_file_and_line(tmp_path):
    path = tmp_path / "latin1.pack"
    path.write_bytes(b"budjam-packing 1\nL 8\nshear 0\nN 1\nnext_id 1\nmeta kind t\xe9rget\n"
                     b"cells id parent x y theta b gamma0\n0 -1 4 4 0 0.5 0.002\nend\n")
    with pytest.raises(budjam.InputError, match=r"latin1.pack:6: meta kind: the value is not valid UTF-8") as e:
        budjam.read_packing(path)
    assert type(e.value) is budjam.InputError


@pytest.mark.parametrize("link", [False, True])
def test_export_refuses_to_overwrite_the_packing_it_reads(tmp_path, link):
    """As `budjam export` does: the output may not be the input file, under any name."""
    source = tmp_path / "p.pack"
    source.write_bytes(PACKING.read_bytes())
    out = source
    if link:
        out = tmp_path / "alias.gsd"
        out.symlink_to(source)
    with pytest.raises(budjam.InputError, match="is the input file"):
        budjam.export(str(source), out, "xyz")
    # A Packing read from the file knows it: the same refusal.
    with pytest.raises(budjam.InputError, match="is the input file"):
        budjam.export(budjam.read_packing(source), out, "xyz")
    assert source.read_bytes() == PACKING.read_bytes()
    budjam.export(str(source), tmp_path / "p.xyz", "xyz")  # another name is written
    assert (tmp_path / "p.xyz").stat().st_size > 0


def test_a_write_past_the_file_size_limit_raises_output_error_and_leaves_no_temporary(tmp_path):
    """As the command line (which ignores SIGXFSZ), the module's writers meet the limit as a failed write:
    CPython ignores SIGXFSZ too."""
    import subprocess
    import sys

    script = ("import resource, budjam\nresource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))\n"
              f"p = budjam.read_packing({str(PACKING)!r})\n"
              "try:\n    p.write('big.pack')\nexcept budjam.OutputError as e:\n    print('OutputError', e)\n")
    r = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("OutputError") and "File too large" in r.stdout
    assert os.listdir(tmp_path) == []


def export_with_a_slow_gsd_writer(tmp_path, script_around, **popen):
    """Runs `script_around(export_call)` in a Python process whose GSD writer (BUDJAM_PYTHON) is a stand-in
    that records its pid and sleeps; returns (process, output directory, writer's pid file) once the writer
    has started, the export's temporary then in the output directory."""
    import shlex
    import subprocess
    import sys
    import time

    started, writer = tmp_path / "started", tmp_path / "slow-python"
    writer.write_text(f"#!/bin/sh\necho $$ > {shlex.quote(str(started))}.new\n"
                      f"mv {shlex.quote(str(started))}.new {shlex.quote(str(started))}\nexec sleep 60\n")
    writer.chmod(0o755)
    out = tmp_path / "out"
    out.mkdir()
    call = f"budjam.export({str(PACKING)!r}, {str(out / 'p.gsd')!r}, 'gsd')"
    proc = subprocess.Popen([sys.executable, "-c", script_around(call)],
                            env={**os.environ, "BUDJAM_PYTHON": str(writer)}, **popen)
    deadline = time.monotonic() + 60
    while not started.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert started.exists(), "the GSD writer never started"
    assert any(out.iterdir()), "no temporary while the writer runs"
    return proc, out, started


def kill_the_writer(started):
    try:
        os.kill(int(started.read_text()), signal.SIGKILL)
    except ProcessLookupError:
        pass


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP], ids=["TERM", "HUP"])
def test_a_python_export_stopped_midway_leaves_no_temporary(tmp_path, sig):
    """SIGTERM or SIGHUP, which end a Python process that does not handle them, remove the temporaries
    of a budjam.export still writing (its GSD writer stands in, slowed), as the command line does."""
    proc, out, started = export_with_a_slow_gsd_writer(tmp_path, lambda call: f"import budjam; {call}")
    proc.send_signal(sig)
    assert proc.wait(timeout=30) == -sig
    kill_the_writer(started)
    assert list(out.iterdir()) == []


def test_ctrl_c_to_the_process_group_during_a_gsd_export_raises_keyboard_interrupt(tmp_path):
    """Ctrl-C reaches the GSD writer as well as Python: the writer it killed is the interrupt, not an OutputError."""
    import subprocess

    proc, out, started = export_with_a_slow_gsd_writer(
        tmp_path, lambda call: ("import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"
                                f"import budjam\ntry: {call}\n"
                                "except KeyboardInterrupt: print('KeyboardInterrupt')\n"
                                "except Exception as e: print(type(e).__name__, e)\n"),
        stdout=subprocess.PIPE, text=True, start_new_session=True)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: Python and its writer
    out_text, _ = proc.communicate(timeout=30)
    kill_the_writer(started)
    assert out_text.strip() == "KeyboardInterrupt", out_text
    assert list(out.iterdir()) == []
