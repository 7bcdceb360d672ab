"""What a run records of where it ran: summary.json's `blas`, the BLAS library (and, for OpenBLAS,
the kernel it runs on this CPU) whose rounding sets the last bits of every factorisation
(docs/speed.md), checked against what ldd, the dynamic loader and OpenBLAS itself say."""
import json
import os
import pathlib
import platform
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest

from conftest import SOURCE_DIR

DEMO = SOURCE_DIR / "data" / "scenes" / "demo.toml"


def recorded_blas(budjam_exe, out, **env):
    r = subprocess.run([budjam_exe, "grow", DEMO, "--out", out, "--quiet", "--set", "growth.max_steps=3"],
                       env={**os.environ, **env}, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads((out / "summary.json").read_text())["blas"]


def recorded_file(blas):
    """The library file a `blas` entry names: all of it, or in parentheses after OpenBLAS's kernel."""
    m = re.fullmatch(r"OpenBLAS \S+, \S+ kernel \((.+)\)", blas)
    return m.group(1) if m else blas


def test_the_recorded_blas_is_the_library_the_loader_binds_to_budjam(budjam_exe, tmp_path):
    ldd = subprocess.run(["ldd", budjam_exe], capture_output=True, text=True, check=True).stdout
    bound = re.search(r"^\s*libblas\.so\.3 => (\S+)", ldd, re.M)
    if not bound:
        pytest.skip("budjam does not load libblas.so.3 (a BLAS linked under another name)")
    assert recorded_file(recorded_blas(budjam_exe, tmp_path / "run")) == os.path.realpath(bound.group(1))


@pytest.mark.skipif(platform.machine() != "x86_64", reason="OpenBLAS kernel names of x86-64")
def test_an_openblas_run_records_the_kernel_openblas_reports_for_it(budjam_exe, tmp_path):
    default = recorded_blas(budjam_exe, tmp_path / "default")
    if not default.startswith("OpenBLAS "):
        pytest.skip(f"the BLAS is not OpenBLAS: {default}")
    library = recorded_file(default)
    for kernel in ("Prescott", "Nehalem"):  # any x86-64 CPU runs both
        blas = recorded_blas(budjam_exe, tmp_path / kernel, OPENBLAS_CORETYPE=kernel)
        # OpenBLAS itself, loaded by another program under the same setting.
        says = subprocess.run(
            [sys.executable, "-c", f"import ctypes; b = ctypes.CDLL({library!r}); b.openblas_get_corename.restype = "
             "ctypes.c_char_p; b.openblas_get_config.restype = ctypes.c_char_p; "
             "print(b.openblas_get_config().decode().split()[1], b.openblas_get_corename().decode())"],
            env={**os.environ, "OPENBLAS_CORETYPE": kernel}, capture_output=True, text=True, check=True).stdout.split()
        assert says[1] == kernel
        assert blas == f"OpenBLAS {says[0]}, {kernel} kernel ({library})"


def test_a_run_on_the_reference_blas_records_that_library(budjam_exe, tmp_path):
    reference = sorted(pathlib.Path("/usr/lib").glob("*/blas/libblas.so.3"))
    if not reference:
        pytest.skip("Debian's reference BLAS (libblas3) is not installed")
    blas = recorded_blas(budjam_exe, tmp_path / "run", LD_LIBRARY_PATH=str(reference[0].parent))
    assert blas == os.path.realpath(reference[0])


def stopped_after_a_checkpoint(budjam_exe, out, env):
    """A demo run under `env` stopped by SIGTERM (a checkpoint of its last complete state, exit 143)."""
    for delay in (0.2, 0.1, 0.05, 0.02, 0.0):
        shutil.rmtree(out, ignore_errors=True)
        proc = subprocess.Popen([budjam_exe, "grow", DEMO, "--out", out, "--quiet"], env={**os.environ, **env},
                                stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while not (out / "steps.csv.partial").exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.001)
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        if proc.wait() == 128 + signal.SIGTERM and (out / "checkpoint.txt").exists():
            return
    pytest.fail("the demo run finished before every signal")


@pytest.mark.skipif(platform.machine() != "x86_64", reason="OpenBLAS kernel names of x86-64")
def test_a_resume_under_another_blas_kernel_says_so_and_one_under_the_same_does_not(budjam_exe, tmp_path):
    if not recorded_blas(budjam_exe, tmp_path / "default").startswith("OpenBLAS "):
        pytest.skip("the BLAS is not OpenBLAS")
    run = tmp_path / "run"
    stopped_after_a_checkpoint(budjam_exe, run, {"OPENBLAS_CORETYPE": "Prescott"})
    for kernel in ("Prescott", "Nehalem"):
        copy = tmp_path / kernel
        shutil.copytree(run, copy)
        r = subprocess.run([budjam_exe, "grow", "--resume", copy, "--quiet"], env={**os.environ,
                           "OPENBLAS_CORETYPE": kernel}, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        notices = [line for line in r.stderr.splitlines() if "another BLAS" in line]
        if kernel == "Prescott":
            assert notices == []
        else:
            assert len(notices) == 1
            assert "Prescott kernel" in notices[0] and "now OpenBLAS" in notices[0] and "Nehalem kernel" in notices[0]
        assert f", {kernel} kernel (" in json.loads((copy / "summary.json").read_text())["blas"]
