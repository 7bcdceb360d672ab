"""A converter (rsvg-convert, the GSD writer) that fails is reported in one line of budjam's own:
the output, the converter, and the converter's last error line or the signal that killed it."""
import os
import stat
import sys

import pytest

from conftest import PACKING


def stand_in(tmp_path, body):
    """An `rsvg-convert` first on PATH that runs `body` (sh)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    exe = bin_dir / "rsvg-convert"
    exe.write_text("#!/bin/sh\n" + body)
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}"}


def render(budjam_exe, out, env):
    import subprocess

    return subprocess.run([budjam_exe, "render", str(PACKING), "-o", str(out)], capture_output=True, text=True,
                          env=env)


@pytest.mark.parametrize("ext", ["png", "pdf"])
def test_failing_converter_gives_one_line_with_output_converter_and_its_last_error(budjam_exe, tmp_path, ext):
    env = stand_in(tmp_path, "echo 'first complaint' >&2\necho 'write error: No space left on device' >&2\n"
                   "echo >&2\nexit 1\n")
    outputs = tmp_path / "out"
    outputs.mkdir()
    out = outputs / f"r.{ext}"
    r = render(budjam_exe, out, env)
    assert r.returncode == 3
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert str(out) in lines[0] and "rsvg-convert" in lines[0]
    assert "No space left on device" in lines[0] and "first complaint" not in lines[0]
    assert list(outputs.iterdir()) == []  # neither the output nor a temporary


def test_converter_killed_by_a_signal_is_named_by_the_signal(budjam_exe, tmp_path):
    env = stand_in(tmp_path, "echo 'about to go' >&2\nkill -KILL $$\n")
    outputs = tmp_path / "out"
    outputs.mkdir()
    out = outputs / "r.png"
    r = render(budjam_exe, out, env)
    assert r.returncode == 3
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert str(out) in lines[0] and "rsvg-convert" in lines[0] and "Killed" in lines[0]
    assert "status 128" not in lines[0]
    assert list(outputs.iterdir()) == []


def test_converter_error_line_is_escaped_and_shortened(budjam_exe, tmp_path):
    env = stand_in(tmp_path, "printf 'bad \\033[2J %s\\n' \"$(head -c 5000 /dev/zero | tr '\\0' x)\" >&2\nexit 1\n")
    outputs = tmp_path / "out"
    outputs.mkdir()
    r = render(budjam_exe, outputs / "r.png", env)
    assert r.returncode == 3
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and "\x1b" not in r.stderr and "\\x1b" in lines[0]
    assert len(lines[0]) < 1000


def test_succeeding_converter_stays_quiet(budjam_exe, tmp_path):
    env = stand_in(tmp_path, "echo 'a warning' >&2\necho drawn\n")
    out = tmp_path / "r.png"
    r = render(budjam_exe, out, env)
    assert r.returncode == 0 and r.stderr == ""
    assert out.read_text() == "drawn\n"


def test_failing_gsd_writer_gives_one_line(budjam_exe, tmp_path):
    # A stand-in interpreter for the GSD writer (BUDJAM_PYTHON) that complains and fails.
    fake = tmp_path / "python"
    fake.write_text("#!/bin/sh\necho 'Traceback (most recent call last):' >&2\necho 'gsd: OSError: disk full' >&2\n"
                    "exit 5\n")
    fake.chmod(0o755)
    import subprocess

    outputs = tmp_path / "out"
    outputs.mkdir()
    out = outputs / "p.gsd"
    r = subprocess.run([budjam_exe, "export", str(PACKING), "--format", "gsd", "--out", str(outputs / "p")], capture_output=True,
                       text=True, env={**os.environ, "BUDJAM_PYTHON": str(fake)})
    assert r.returncode == 3
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert str(out) in lines[0] and "gsd: OSError: disk full" in lines[0]
    assert list(outputs.iterdir()) == []


@pytest.mark.parametrize("command", ["render", "export"])
def test_a_failed_conversion_leaves_no_directory_it_made(budjam_exe, tmp_path, command):
    """Nothing written: the directories budjam made for the output are removed again, deepest first, and
    one that already existed stays."""
    import subprocess

    fake = tmp_path / "python"
    fake.write_text("#!/bin/sh\nexit 4\n")
    fake.chmod(0o755)
    env = {**stand_in(tmp_path, "exit 1\n"), "BUDJAM_PYTHON": str(fake)}
    (tmp_path / "there").mkdir()
    args = {"render": ["render", PACKING, "-o", tmp_path / "there" / "nd3" / "nd4" / "x.png"],
            "export": ["export", PACKING, "--format", "gsd", "--out", tmp_path / "there" / "nd5" / "nd6" / "g"]}
    r = subprocess.run([budjam_exe, *map(str, args[command])], capture_output=True, text=True, env=env)
    assert r.returncode == 3 and len(r.stderr.splitlines()) == 1, r.stderr
    assert list((tmp_path / "there").iterdir()) == []


def test_a_converter_starts_with_the_default_dispositions_of_sigpipe_and_sigxfsz(budjam_exe, tmp_path):
    """budjam ignores SIGPIPE and SIGXFSZ (a failed write is an output error); ignored signals stay ignored
    across exec, so the converter is given the defaults back."""
    env = stand_in(tmp_path, "echo ignored $(awk '/SigIgn/ {print $2}' /proc/$$/status) >&2\nexit 1\n")
    r = render(budjam_exe, tmp_path / "r.png", env)
    assert r.returncode == 3
    ignored = int(r.stderr.split("ignored ")[1].split()[0], 16)
    for sig in (13, 25):  # SIGPIPE, SIGXFSZ
        assert not ignored & (1 << (sig - 1)), r.stderr
