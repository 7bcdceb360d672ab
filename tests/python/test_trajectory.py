"""The trajectory observer ([observe] trajectory_every): trajectory.xyz read back by ASE, frames
at the sampled steps and at every event state, identical to `budjam export` of the event packings,
and byte-identical after a kill and --resume."""
import json
import signal
import subprocess
import time

import ase.io
import numpy as np
import pytest

from conftest import SOURCE_DIR, assert_gsd_frames_are_the_xyz_frames

SCENE = SOURCE_DIR / "data" / "scenes" / "demo.toml"
SETTINGS = ["--set", "observe.trajectory_every=100", "--set", "observe.checkpoint_every=50"]


@pytest.fixture(scope="module")
def reference(run_budjam, tmp_path_factory):
    out = tmp_path_factory.mktemp("trajectory") / "ref"
    run_budjam("grow", SCENE, "--out", out, "--quiet", *SETTINGS)
    return out


def test_frames_at_sampled_steps_and_events(reference):
    frames = ase.io.read(reference / "trajectory.xyz", index=":", format="extxyz")
    steps = [f.info["step"] for f in frames]
    assert steps == sorted(set(steps))  # one frame per state, in order
    summary = json.loads((reference / "summary.json").read_text())
    assert {0, 100, 200} <= set(steps)
    # Every event state of the run has its frame: jamming, each target and φ_2 if the run reached it.
    events = [summary["step_J"]] + [t["step"] for t in summary["targets"]]
    events += [summary["step_2"]] if summary["step_2"] is not None else []
    assert set(events) <= set(steps)
    assert steps[-1] == summary["accepted_steps"]  # the last state
    assert not (reference / "trajectory.xyz.partial").exists()


def test_event_frame_is_the_export_of_the_event_packing(reference, run_budjam, tmp_path):
    summary = json.loads((reference / "summary.json").read_text())
    frames = {f.info["step"]: f for f in ase.io.read(reference / "trajectory.xyz", index=":", format="extxyz")}
    run_budjam("export", reference / "packings" / "jammed.pack", "--format", "xyz", "--out", tmp_path / "j")
    exported = ase.io.read(tmp_path / "j.xyz", format="extxyz")
    at_jamming = frames[summary["step_J"]]
    np.testing.assert_array_equal(at_jamming.positions, exported.positions)
    for name in ("radius", "cell_id", "id", "rigid_cluster", "rattler", "type"):
        np.testing.assert_array_equal(at_jamming.arrays[name], exported.arrays[name])


def test_killed_and_resumed_run_writes_the_same_trajectory(reference, budjam_exe, run_budjam, tmp_path):
    # Killed a little after its first checkpoint or, on a machine fast enough to finish by then, at it.
    for delay in (0.05, 0.0):
        out = tmp_path / f"killed-{delay}"
        proc = subprocess.Popen([budjam_exe, "grow", SCENE, "--out", out, "--quiet", *SETTINGS])
        deadline = time.monotonic() + 120
        while not (out / "checkpoint.txt").exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.001)
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if proc.returncode == -signal.SIGKILL:
            break
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    assert not (out / "trajectory.xyz").exists()
    run_budjam("grow", "--resume", out, "--quiet")
    assert (out / "trajectory.xyz").read_bytes() == (reference / "trajectory.xyz").read_bytes()


def test_the_trajectory_exports_to_one_gsd_file_with_every_frame(reference, run_budjam, tmp_path):
    """N changes from frame to frame (divisions); gsd reads every frame as ASE reads the XYZ."""
    run_budjam("export", reference / "trajectory.xyz", "--format", "gsd", "--out", tmp_path / "traj")
    assert assert_gsd_frames_are_the_xyz_frames(tmp_path / "traj.gsd", reference / "trajectory.xyz") > 3


def test_a_runs_trajectory_exports_by_default_to_the_runs_own_trajectory_gsd(reference, run_budjam, tmp_path):
    """`budjam export RUN/trajectory.xyz --format gsd` without --out writes RUN/trajectory.gsd (an entry
    the run declares), also run from inside the run; any other output at the run's top level is still
    refused, and a link at trajectory.gsd is refused without writing through it."""
    import os
    import shutil

    run = tmp_path / "run"
    shutil.copytree(reference, run, symlinks=True)
    (run / "trajectory.gsd").unlink(missing_ok=True)
    before = sorted(p.name for p in run.iterdir())
    run_budjam("export", run / "trajectory.xyz", "--format", "gsd")
    assert assert_gsd_frames_are_the_xyz_frames(run / "trajectory.gsd", run / "trajectory.xyz") > 3
    assert sorted(p.name for p in run.iterdir()) == sorted(before + ["trajectory.gsd"])  # no temporary left
    (run / "trajectory.gsd").unlink()
    run_budjam("export", "trajectory.xyz", "--format", "gsd", cwd=run)
    assert (run / "trajectory.gsd").is_file()
    r = run_budjam("export", run / "trajectory.xyz", "--format", "gsd", "--out", run / "other", check=False)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    assert "budjam run directory" in r.stderr
    # Another format is refused for what it is, with or without an --out (whose default,
    # RUN/trajectory.vtk, would also be refused as an entry of the run).
    for args in (["--format", "xyz", "--out", run / "trajectory"], ["--format", "vtk"], ["--format", "xyz"]):
        r = run_budjam("export", run / "trajectory.xyz", *args, check=False)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
        assert "exports to gsd only" in r.stderr
    (run / "trajectory.gsd").unlink()
    os.symlink(tmp_path / "elsewhere.gsd", run / "trajectory.gsd")
    r = run_budjam("export", run / "trajectory.xyz", "--format", "gsd", check=False)
    assert r.returncode == 2 and "symbolic link" in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
    assert not (tmp_path / "elsewhere.gsd").exists() and (run / "trajectory.gsd").is_symlink()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL], ids=["INT", "TERM", "KILL"])
def test_an_export_of_a_runs_trajectory_stopped_midway_leaves_the_run_as_it_was(reference, budjam_exe, run_budjam,
                                                                                tmp_path, sig):
    """Stopped by SIGINT or SIGTERM while its GSD writer runs, the export removes its temporaries and
    empties the run's list of them (a name left listed would make the next claim of the run remove a
    file a user has created under it since); killed, it leaves them listed, and the next export
    removes exactly those before it writes."""
    import os
    import shlex
    import shutil

    run = tmp_path / "run"
    shutil.copytree(reference, run, symlinks=True)
    (run / "trajectory.gsd").unlink(missing_ok=True)
    before = sorted(p.name for p in run.iterdir())
    assert ".budjam-temporaries" in before
    started, writer = tmp_path / "started", tmp_path / "slow-python"
    writer.write_text(f"#!/bin/sh\necho $$ > {shlex.quote(str(started))}.new\n"
                      f"mv {shlex.quote(str(started))}.new {shlex.quote(str(started))}\nexec sleep 60\n")
    writer.chmod(0o755)
    proc = subprocess.Popen([budjam_exe, "export", run / "trajectory.xyz", "--format", "gsd"],
                            env={**os.environ, "BUDJAM_PYTHON": str(writer)})
    deadline = time.monotonic() + 60
    while not started.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert started.exists(), "the GSD writer never started"
    proc.send_signal(sig)
    assert proc.wait(timeout=30) == -sig
    try:
        os.kill(int(started.read_text()), signal.SIGKILL)  # an orphan of the killed export
    except ProcessLookupError:
        pass
    left = sorted(p.name for p in run.iterdir() if p.name not in before)
    listed = sorted((run / ".budjam-temporaries").read_text().split())
    if sig == signal.SIGKILL:
        assert len(left) == 2 and listed == left  # the frames it passes on and the GSD file
    else:
        assert left == [] and listed == []
    user = run / "packings" / ".mine.tmp-abcdef"  # a user's file named like a temporary stays
    user.write_text("the user's\n")
    run_budjam("export", run / "trajectory.xyz", "--format", "gsd")
    assert sorted(p.name for p in run.iterdir()) == sorted(before + ["trajectory.gsd"])
    assert (run / ".budjam-temporaries").read_text() == "" and user.read_text() == "the user's\n"
