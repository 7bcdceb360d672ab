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

    def run(*args, check=True):
        r = subprocess.run([budjam_exe, *map(str, args)], capture_output=True, text=True)
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
