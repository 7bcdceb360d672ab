"""Shared by the pytest suites that ctest runs: the `budjam` executable and the test packings."""
import json
import os
import pathlib
import shutil
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("BUDJAM_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
PACKING = SOURCE_DIR / "tests" / "data" / "saddle_jamming_L15_seed3.pack"


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: grows a run first (ctest label slow)")


@pytest.fixture(scope="session")
def budjam_exe():
    exe = os.environ.get("BUDJAM_EXE")
    if not exe:
        pytest.fail("BUDJAM_EXE is not set: run these tests through ctest")
    return exe


@pytest.fixture(scope="session")
def run_budjam(budjam_exe):
    """Runs `budjam ARGS...`; returns the CompletedProcess (stdout/stderr as text)."""

    def run(*args, check=True, cwd=None):
        r = subprocess.run([budjam_exe, *map(str, args)], capture_output=True, text=True, cwd=cwd)
        if check and r.returncode != 0:
            pytest.fail(f"budjam {' '.join(map(str, args))} exited {r.returncode}: {r.stderr}")
        return r

    return run


@pytest.fixture(scope="session")
def sheared_packing(tmp_path_factory):
    """The jammed test packing under a Lees–Edwards shear γ = 1: the same lattice of images, so the same
    contacts (a shear that moved the images would stack cells across the boundary, which the reader
    refuses), with every image shifted by one box in x."""
    text = PACKING.read_text().replace("\nshear 0\n", "\nshear 1\n", 1)
    assert "\nshear 1\n" in text
    path = tmp_path_factory.mktemp("sheared") / "sheared.pack"
    path.write_text(text)
    return path


@pytest.fixture(scope="session")
def run_dir(run_budjam, tmp_path_factory):
    """A small growth run (L = 8, to the Δφ targets and φ_2) with moduli, rigidity events and trials."""
    out = tmp_path_factory.mktemp("run") / "demo"
    run_budjam("grow", SOURCE_DIR / "data" / "scenes" / "demo.toml", "--out", out, "--quiet",
               "--set", "observe.moduli.at_targets=true", "--set", "observe.rigidity_events=true",
               "--set", "observe.trials=true")
    return out


@pytest.fixture(scope="session")
def relaxed(run_dir, tmp_path_factory):
    """A relaxed packing above jamming, alone in a directory (dos writes beside it)."""
    path = tmp_path_factory.mktemp("relaxed") / "target.pack"
    shutil.copy(run_dir / "packings" / "target_1.pack", path)
    return path


def rigidity_json(run_budjam, packing):
    return json.loads(run_budjam("rigidity", packing, "--json").stdout)


def assert_gsd_frames_are_the_xyz_frames(gsd_path, xyz_path):
    """Every frame of the GSD trajectory, as gsd reads it, is the XYZ frame ASE reads: step, N, box,
    positions (float32, box centred on 0), kinds, diameters and the per-lobe fields."""
    import ase.io
    import gsd.hoomd
    import numpy as np

    xyz = ase.io.read(xyz_path, index=":", format="extxyz")
    traj = gsd.hoomd.open(str(gsd_path), "rb")
    assert len(traj) == len(xyz)
    for frame, atoms in zip(traj, xyz):
        L, xy = atoms.cell[0][0], atoms.cell[1][0] / atoms.cell[0][0]
        assert frame.configuration.step == atoms.info["step"]
        assert frame.particles.N == len(atoms)
        np.testing.assert_allclose(frame.configuration.box, [L, L, 1, xy, 0, 0], rtol=1e-6)
        centred = atoms.positions[:, :2] - [0.5 * L * (1 + xy), 0.5 * L]
        np.testing.assert_allclose(frame.particles.position[:, :2], centred, rtol=0, atol=1e-6 * L)
        kinds = np.array(frame.particles.types)[frame.particles.typeid]
        np.testing.assert_array_equal(kinds, atoms.arrays["type"])
        np.testing.assert_allclose(frame.particles.diameter, 2 * atoms.arrays["radius"], rtol=1e-6)
        for name in ("cell_id", "id", "rigid_cluster", "rattler"):
            np.testing.assert_array_equal(frame.log[f"particles/{name}"], atoms.arrays[name], err_msg=name)
    return len(traj)

