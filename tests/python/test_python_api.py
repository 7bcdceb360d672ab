"""The Python module as users of HOOMD-blue, ASE and pandas expect it: paths wherever a packing
is, typed metadata, dict overrides, events in physical order, in-memory bridges to ase / gsd /
pandas that equal what those packages read from budjam's files, and result dicts keyed as the
command line's JSON."""
import json
import pathlib
import re
import shutil

import ase.io
import gsd.hoomd
import numpy as np
import pandas
import pytest

import budjam
from conftest import PACKING, SOURCE_DIR

DEMO = SOURCE_DIR / "data" / "scenes" / "demo.toml"


@pytest.fixture(scope="module")
def stepped_packing(tmp_path_factory):
    """The test packing with a growth step in its metadata, as a run's packings have."""
    p = budjam.read_packing(PACKING)
    path = tmp_path_factory.mktemp("stepped") / "stepped.pack"
    budjam.Packing(p.L, p.x, p.y, p.theta, p.b, p.gamma0, meta={**p.meta, "step": 1817}).write(path)
    return path


@pytest.fixture(scope="module")
def exported(stepped_packing, run_budjam, tmp_path_factory):
    """The stepped packing exported by the command line as XYZ and GSD, read by ASE and gsd."""
    base = tmp_path_factory.mktemp("exported") / "p"
    for fmt in ("xyz", "gsd"):
        run_budjam("export", stepped_packing, "--format", fmt, "--out", base)
    frame = gsd.hoomd.open(str(base) + ".gsd", "rb")[0]
    return {"xyz": ase.io.read(str(base) + ".xyz", format="extxyz"), "gsd": frame}


def test_version_is_the_command_lines(run_budjam):
    assert run_budjam("--version").stdout.split() == ["budjam", budjam.__version__]


def test_blas_is_the_one_a_run_of_the_command_line_records(run_dir):
    assert budjam.blas() == json.loads((run_dir / "summary.json").read_text())["blas"]


@pytest.mark.parametrize("as_path", [str, pathlib.Path])
def test_every_function_of_a_packing_accepts_its_path(as_path):
    p = budjam.read_packing(PACKING)
    np.testing.assert_array_equal(budjam.rigidity(as_path(PACKING))["lobe_cluster"], budjam.rigidity(p)["lobe_cluster"])
    np.testing.assert_array_equal(budjam.contacts(as_path(PACKING))["force"], budjam.contacts(p)["force"])
    np.testing.assert_array_equal(budjam.particle_frame(as_path(PACKING))["x"], budjam.particle_frame(p)["x"])
    assert budjam.moduli(as_path(PACKING)) == budjam.moduli(p)


def test_a_path_to_a_missing_packing_raises_input_error_naming_it(tmp_path):
    with pytest.raises(budjam.InputError, match="nowhere.pack"):
        budjam.rigidity(tmp_path / "nowhere.pack")


def test_meta_values_are_numbers_where_the_file_holds_numbers_and_round_trip(stepped_packing):
    p = budjam.read_packing(stepped_packing)
    assert p.meta["step"] == 1817 and isinstance(p.meta["step"], int)
    assert isinstance(p.meta["phi"], float) and isinstance(p.meta["Z"], float)
    assert p.meta["phase"] == "jammed" and p.meta["P0"] == "none"
    copy = budjam.Packing(p.L, p.x, p.y, p.theta, p.b, p.gamma0, meta=p.meta)
    assert copy.meta == p.meta


def test_moduli_is_the_json_of_budjam_moduli_key_for_key(run_budjam):
    cli = json.loads(run_budjam("moduli", PACKING, "--json", check=False).stdout)
    del cli["file"]
    assert budjam.moduli(PACKING) == cli


def test_grow_takes_overrides_as_a_dict_a_string_or_a_list():
    runs = [[(e["kind"], e["step"], e["phi"]) for e in budjam.grow(DEMO, set=overrides)]
            for overrides in ({"growth.max_steps": 40}, "growth.max_steps=40", ["growth.max_steps=40"])]
    assert runs[0] == runs[1] == runs[2]
    assert runs[0][-1][0] == "stopped"


def test_grow_dict_values_are_written_as_the_scene_would_hold_them():
    """A float, None (no feedback) and a bool reach the scene; a bad key is the --set error."""
    status = budjam.grow(DEMO, set={"growth.P0": None, "growth.max_steps": 30, "observe.bud_events": False},
                         callback=lambda e: None)
    assert status == "step_limit"
    with pytest.raises(budjam.InputError, match=r"growth\.P0: must be at least 1e-300.*\(got -0\.001\)"):
        budjam.grow(DEMO, set={"growth.P0": -1e-3})
    with pytest.raises(budjam.InputError, match=r"--set growth\.nope=1: growth\.nope: unknown key"):
        budjam.grow(DEMO, set={"growth.nope": 1})


def test_ctrl_c_inside_growth_raises_keyboard_interrupt_before_another_event_and_ends_the_growth():
    # A SIGINT while the driver relaxes (between two events) is Python's at once: no event is delivered
    # after it, and the growth, left inside a step, refuses to go on.
    import signal
    fired = []

    def interrupt(signum, frame):
        fired.append(True)
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    growth = budjam.grow(SOURCE_DIR / "data" / "scenes" / "paper-L15.toml",
                         set={"jamming.targets": [1e-3, 1e-2, 3e-2, 6e-2, 0.12]})
    after = []
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.3)
        with pytest.raises(KeyboardInterrupt):
            for event in growth:
                if fired:
                    after.append(event["kind"])
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert fired and after == []
    with pytest.raises(RuntimeError, match="interrupted"):
        next(growth)


def test_buds_tagged_at_a_jamming_come_after_its_jammed_event():
    events = list(budjam.grow(DEMO))
    kinds = [e["kind"] for e in events]
    assert "bud_tagged" in kinds and "jammed" in kinds
    for k, e in enumerate(events):
        if e["kind"] == "bud_tagged":
            before = [b for b in events[:k] if b["kind"] != "bud_tagged"][-1]
            assert before["kind"] == "jammed" and before["step"] == e["step"]


@pytest.fixture(scope="module")
def demo_run(run_budjam, tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "demo"
    run_budjam("grow", DEMO, "--out", out, "--quiet")
    return out


def test_load_run_reads_only_the_tables_budjam_wrote(demo_run, tmp_path):
    """A user's own CSV in the run directory, even one no CSV reader accepts, is not read."""
    out = shutil.copytree(demo_run, tmp_path / "demo")
    (out / "my_notes.csv").write_bytes(b"not, a\n budjam, table, at all\n\xff\n")
    run = budjam.load_run(out)
    assert set(run.tables) == {"steps", "divisions", "bud_events"}
    assert run.summary == json.loads((out / "summary.json").read_text())
    steps = pandas.read_csv(out / "steps.csv", float_precision="round_trip")
    pandas.testing.assert_frame_equal(run.steps, steps)


def test_load_run_names_a_damaged_log_with_control_bytes_escaped(demo_run, tmp_path):
    out = shutil.copytree(demo_run, tmp_path / "demo\x1b[2J")
    with open(out / "bud_events.csv", "a") as log:
        log.write("1,2\n")
    with pytest.raises(budjam.InputError, match=r"demo\\x1b\[2J/bud_events\.csv:\d+: 2 fields, header has") as e:
        budjam.load_run(out)
    assert not any(ord(c) < 0x20 for c in str(e.value))


def test_load_run_refuses_a_short_row_that_pandas_would_fill_with_nan(demo_run, tmp_path):
    """budjam's reader (that of `budjam analyse`) reads the tables, not pandas' more lenient one."""
    out = shutil.copytree(demo_run, tmp_path / "demo")
    columns = (out / "divisions.csv").read_text().splitlines()[0].split(",")
    with open(out / "divisions.csv", "a") as log:
        log.write(",".join(["1"] * (len(columns) - 1)) + "\n")
    assert pandas.read_csv(out / "divisions.csv").iloc[-1].isna().sum() == 1
    with pytest.raises(budjam.InputError, match=r"divisions\.csv:\d+: \d+ fields, header has"):
        budjam.load_run(out)


def test_to_ase_equals_what_ase_reads_from_the_exported_xyz(stepped_packing, exported):
    atoms, read = budjam.read_packing(stepped_packing).to_ase(), exported["xyz"]
    np.testing.assert_array_equal(atoms.positions, read.positions)
    np.testing.assert_array_equal(atoms.cell[:], read.cell[:])
    assert list(atoms.pbc) == list(read.pbc)
    for column in ("type", "radius", "cell_id", "id", "rigid_cluster", "rattler"):
        np.testing.assert_array_equal(atoms.arrays[column], read.arrays[column], err_msg=column)
    assert atoms.info["step"] == read.info["step"] == 1817


def test_to_gsd_frame_equals_the_frame_gsd_reads_from_the_exported_file(stepped_packing, exported):
    frame, read = budjam.read_packing(stepped_packing).to_gsd_frame(), exported["gsd"]
    assert frame.configuration.step == read.configuration.step == 1817
    np.testing.assert_array_equal(frame.configuration.box, read.configuration.box)
    np.testing.assert_array_equal(np.float32(frame.particles.position), read.particles.position)
    np.testing.assert_array_equal(frame.particles.image, read.particles.image)
    np.testing.assert_array_equal(np.float32(frame.particles.diameter), read.particles.diameter)
    np.testing.assert_array_equal(frame.bonds.group, read.bonds.group)
    for key in ("particles/rigid_cluster", "particles/id", "bonds/force"):
        np.testing.assert_array_equal(frame.log[key], read.log[key], err_msg=key)


def test_particles_dataframe_has_one_row_per_lobe_as_exported(stepped_packing, exported):
    p = budjam.read_packing(stepped_packing)
    df, read = p.particles(), exported["xyz"]
    assert isinstance(df, pandas.DataFrame) and len(df) == 2 * p.N
    assert list(df["type"]) == list(read.arrays["type"])
    np.testing.assert_array_equal(df["wrapped_x"], read.positions[:, 0])
    np.testing.assert_array_equal(df["radius"], p.lobes()["radius"])
    np.testing.assert_array_equal(df["rigid_cluster"], read.arrays["rigid_cluster"])


def test_particle_frame_has_exactly_the_keys_python_md_lists(stepped_packing):
    text = (SOURCE_DIR / "docs" / "python.md").read_text()
    start = text.index("`particle_frame(p)` gives")
    listed = set(re.findall(r"`(\w+)`", text[start:text.index("The export's", start)]))
    frame = budjam.particle_frame(stepped_packing)
    assert set(frame) == listed
    assert all(len(frame[k]) == 2 * budjam.read_packing(stepped_packing).N for k in ("x", "rigid_cluster", "rattler"))
