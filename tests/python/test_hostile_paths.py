"""Output and input paths a hostile user gives every command: names that do not name a file, a
directory where a file is expected, names too long for a temporary beside them, inputs that are not
regular files. Each is one line `budjam: error: ...` naming the path, exit 2, nothing written and
every file that was there byte-identical (docs/files.md, "Crash safety")."""
import os
import shlex
import shutil
import stat
import subprocess

import pytest

from conftest import SOURCE_DIR

PACKING = SOURCE_DIR / "tests" / "data" / "negative_G_target_L8.pack"


def snapshot(root):
    """Every entry under root (links not followed): kind and content."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            path = os.path.join(dirpath, name)
            st = os.lstat(path)
            if stat.S_ISLNK(st.st_mode):
                out[path] = ("link", os.readlink(path))
            elif stat.S_ISREG(st.st_mode):
                with open(path, "rb") as f:
                    out[path] = ("file", f.read())
            else:
                out[path] = ("dir" if stat.S_ISDIR(st.st_mode) else "other", None)
    return out


def assert_refused(r, *words):
    assert r.returncode == 2, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("budjam: error: "), r.stderr
    assert "internal" not in lines[0]
    for w in words:
        assert w in lines[0], lines[0]


# (command, arguments before --out, extensions written, option)
BASE_COMMANDS = [
    ("rigidity", [PACKING], [".json", ".csv"], "--out"),
    ("dos", [PACKING], [".json", ".csv"], "--out"),
    ("moduli", [PACKING], [".json"], "--out"),
]


@pytest.mark.parametrize("command,args,extensions,option", BASE_COMMANDS)
@pytest.mark.parametrize("base", ["d/", ".", "..", "sub/.", "x" * 250, ".json", "d/.csv"])
def test_a_base_that_names_no_file_or_too_long_a_name_is_refused(run_budjam, tmp_path, command, args, extensions,
                                                                 option, base):
    (tmp_path / "d").mkdir()
    (tmp_path / "sub").mkdir()
    before = snapshot(tmp_path)
    r = run_budjam(command, *args, option, f"{tmp_path}/{base}", check=False)
    assert_refused(r, option)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("name", [".png", ".svg", "d/.pdf", "d/", ".", "x" * 250 + ".svg"])
def test_a_render_output_that_names_no_file_is_refused(run_budjam, tmp_path, name):
    (tmp_path / "d").mkdir()
    before = snapshot(tmp_path)
    r = run_budjam("render", PACKING, "-o", f"{tmp_path}/{name}", check=False)
    assert_refused(r, "-o")
    if name.split("/")[-1] in (".png", ".svg", ".pdf"):
        assert "no file name before the extension" in r.stderr
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("command,args,extensions,option", BASE_COMMANDS)
def test_a_directory_where_a_result_file_goes_is_refused_before_anything_is_written(run_budjam, tmp_path, command,
                                                                                    args, extensions, option):
    for ext in extensions:
        for other in extensions:
            (tmp_path / ("r" + other)).unlink(missing_ok=True)
            if other != ext:
                (tmp_path / ("r" + other)).write_text("the user's\n")
        (tmp_path / ("r" + ext)).mkdir()
        before = snapshot(tmp_path)
        r = run_budjam(command, *args, option, tmp_path / "r", check=False)
        assert_refused(r, f"r{ext}", "is a directory")
        assert snapshot(tmp_path) == before
        (tmp_path / ("r" + ext)).rmdir()


def test_survival_refuses_a_base_that_names_a_directory(run_budjam, run_dir, tmp_path):
    before = snapshot(tmp_path)
    r = run_budjam("survival", run_dir, "-o", str(tmp_path) + "/", check=False)
    assert_refused(r)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("kind", ["fifo", "device"])
@pytest.mark.parametrize("command", ["rigidity", "dos", "moduli", "render", "export", "validate"])
def test_an_input_that_is_not_a_regular_file_is_refused_at_once(budjam_exe, tmp_path, command, kind):
    if kind == "fifo":
        path = tmp_path / "p.pack"
        os.mkfifo(path)
    else:
        path = "/dev/zero"
    extra = {"render": ["-o", tmp_path / "p.svg"], "export": ["--format", "xyz", "--out", tmp_path / "p"]}
    before = snapshot(tmp_path)
    # a reader would wait for a writer (FIFO) or fill the memory (/dev/zero)
    r = subprocess.run([budjam_exe, command, str(path), *map(str, extra.get(command, []))], capture_output=True,
                       text=True, timeout=60)
    assert_refused(r, str(path), "not a regular file")
    assert snapshot(tmp_path) == before


def test_an_input_file_beyond_the_size_limit_is_refused_without_reading_it(run_budjam, tmp_path):
    huge = tmp_path / "huge.pack"
    with open(huge, "wb") as f:
        f.truncate(64 << 30)  # sparse: no disk used
    r = run_budjam("rigidity", huge, check=False)
    assert_refused(r, str(huge), "larger than")


@pytest.mark.parametrize("command", ["analyse", "accuracy", "grow"])
def test_an_output_directory_that_is_a_file_or_a_dangling_link_is_refused(run_budjam, run_dir, tmp_path, command):
    """Also a directory to be created under either: the message names the part that stops it."""
    (tmp_path / "file").write_text("the user's\n")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    args = {"analyse": [run_dir], "accuracy": ["--packings", f"x={run_dir}"],
            "grow": [SOURCE_DIR / "data" / "scenes" / "demo.toml"]}[command]
    before = snapshot(tmp_path)
    for out in ["file", "dangling", "file/sub", "dangling/sub"]:
        r = run_budjam(command, *args, "--out", tmp_path / out, check=False)
        assert_refused(r, out, *(["symbolic link to nothing"] if out.startswith("dangling") else []))
        assert snapshot(tmp_path) == before


def test_analyse_refuses_a_directory_where_a_table_goes_before_writing_any(run_budjam, run_dir, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "targets.csv").mkdir()
    (out / "runs.csv").write_text("an earlier analysis\n")
    before = snapshot(tmp_path)
    r = run_budjam("analyse", run_dir, "--out", out, "--resamples", "10", check=False)
    assert_refused(r, "targets.csv", "is a directory")
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("command,output", [("render", ["-o", "p.svg"]), ("render", ["-o", "q.svg", "--png"]),
                                           ("moduli", ["--out", "p"]), ("dos", ["--out", "p"]),
                                           ("rigidity", ["--out", "p"]), ("export", ["--format", "xyz", "--out", "p"]),
                                           ("moduli", ["--out", "link"])])
def test_an_output_that_is_the_commands_input_file_is_refused_and_the_input_kept(run_budjam, tmp_path, command,
                                                                                 output):
    """The input under an output's name (p.svg, p.json, p.csv, q.png, p.xyz), or reached through a link or a
    hard link: writing the output would replace the input, so the command refuses before any work."""
    data = PACKING.read_bytes()
    ext = {"render": ".png" if "--png" in output else ".svg", "export": ".xyz"}.get(command, ".json")
    if command in ("dos", "rigidity"):
        ext = ".csv"
    name = output[output.index("--out") + 1 if "--out" in output else output.index("-o") + 1]
    stem = name.rsplit(".", 1)[0] if "." in name else name
    input_path = tmp_path / ("p" + ext)
    input_path.write_bytes(data)
    if stem == "link":
        os.link(input_path, tmp_path / "link.json")
    if stem == "q":
        os.symlink(input_path, tmp_path / "q.png")
    before = snapshot(tmp_path)
    r = run_budjam(command, input_path, *output, check=False, cwd=tmp_path)
    assert_refused(r, "is the input file")
    assert snapshot(tmp_path) == before
    assert input_path.read_bytes() == data


@pytest.mark.parametrize("name", ["summary", "bud_events", "steps", "divisions"])
def test_survival_refuses_an_output_that_is_one_of_the_runs_files(run_budjam, run_dir, tmp_path, name):
    """Also in a run without its marker (where the top-level rule does not apply): the output would replace
    the file survival reads."""
    run = tmp_path / "run"
    shutil.copytree(run_dir, run)
    (run / ".budjam-run").unlink()
    before = snapshot(tmp_path)
    r = run_budjam("survival", run, "-o", run / name, check=False)
    assert_refused(r, "is the input file")
    assert snapshot(tmp_path) == before


def test_analyse_refuses_an_output_that_is_one_of_the_runs_files(run_budjam, run_dir, tmp_path):
    """analyse's dos.csv has the name of a run's own log: --out in a run without its marker (holding an earlier
    analysis, so that the directory is analyse's to write) may not replace it."""
    run = tmp_path / "run"
    shutil.copytree(run_dir, run)
    (run / ".budjam-run").unlink()
    (run / "dos.csv").write_text("step,phi\n")
    (run / "analysis.json").write_text('{"format": "budjam-analysis", "version": 1, "groups": []}')
    before = snapshot(tmp_path)
    r = run_budjam("analyse", run, "--out", run, "--resamples", "10", check=False)
    assert_refused(r, "is the input file", "dos.csv")
    assert snapshot(tmp_path) == before


def test_analyse_refuses_an_output_that_is_a_packing_sidecar_it_reads(run_budjam, run_dir, tmp_path):
    """A table that is (a hard link to) a packing's moduli file of a run it reads: replacing it would
    change that run's input."""
    run = tmp_path / "run"
    shutil.copytree(run_dir, run)
    sidecar = next((run / "packings").glob("*.pack")).with_suffix(".moduli.json")
    sidecar.write_text('{"B": 1, "G": 1, "N": 1, "L": 1, "phi": 1}')
    out = tmp_path / "out"
    out.mkdir()
    (out / "analysis.json").write_text('{"format": "budjam-analysis", "version": 1, "groups": []}')
    os.link(sidecar, out / "runs.csv")
    before = snapshot(tmp_path)
    r = run_budjam("analyse", run, "--out", out, "--resamples", "10", check=False)
    assert_refused(r, "is the input file")
    assert snapshot(tmp_path) == before


def limited_to_4_kib():
    import resource

    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def test_a_file_size_limit_is_an_output_failure_not_a_signal(budjam_exe, tmp_path):
    """SIGXFSZ is ignored: the write fails with EFBIG and takes the path of every failed output (one line,
    exit 3, no temporary left)."""
    r = subprocess.run([budjam_exe, "export", str(PACKING), "--format", "xyz", "--out", "big"], cwd=tmp_path,
                       capture_output=True, text=True, preexec_fn=limited_to_4_kib)
    assert r.returncode == 3, r.stderr
    assert r.stderr.splitlines() == [r.stderr.strip()] and "File too large" in r.stderr
    assert os.listdir(tmp_path) == []


def test_a_run_past_the_file_size_limit_exits_3_and_leaves_whole_rows(budjam_exe, tmp_path):
    r = subprocess.run([budjam_exe, "grow", str(SOURCE_DIR / "data" / "scenes" / "demo.toml"), "--quiet", "--out",
                        "run"], cwd=tmp_path, capture_output=True, text=True, preexec_fn=limited_to_4_kib)
    assert r.returncode == 3, r.stderr
    assert len(r.stderr.splitlines()) == 1 and "File too large" in r.stderr
    steps = (tmp_path / "run" / "steps.csv.partial").read_bytes()
    assert steps.endswith(b"\n")
    assert not [p for p in (tmp_path / "run").rglob("*") if ".tmp-" in p.name]


def closed_pipe():
    """The write end of a pipe whose reader is gone."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    return write_end


def test_a_result_on_a_closed_pipe_is_exit_3_not_sigpipe(budjam_exe):
    out = closed_pipe()
    try:
        r = subprocess.run([budjam_exe, "rigidity", str(PACKING), "--json"], stdout=out, stderr=subprocess.PIPE,
                           text=True)
    finally:
        os.close(out)
    assert r.returncode == 3, r.stderr
    assert r.stderr.splitlines()[-1].startswith("budjam: error: standard output: cannot write")


def test_a_run_whose_progress_reader_went_away_goes_on(budjam_exe, tmp_path):
    err = closed_pipe()
    try:
        r = subprocess.run([budjam_exe, "grow", str(SOURCE_DIR / "data" / "scenes" / "demo.toml"), "--out",
                            tmp_path / "run"], stdout=subprocess.PIPE, stderr=err)
    finally:
        os.close(err)
    assert r.returncode == 0
    assert (tmp_path / "run" / "summary.json").is_file()


def test_a_full_disk_names_the_file_whose_write_failed(budjam_exe, tmp_path):
    """On a filesystem too small for a run (a tmpfs in a mount namespace of its own), the one error line
    names the file budjam could not write, whichever it is, never just the run directory."""
    disk = tmp_path / "disk"
    disk.mkdir()
    for size in ("8k", "28k", "170k"):
        script = (f"mount -t tmpfs -o size={size} tmpfs {shlex.quote(str(disk))} && "
                  f"exec {shlex.quote(str(budjam_exe))} grow {shlex.quote(str(SOURCE_DIR / 'data' / 'scenes' / 'demo.toml'))} "
                  f"--quiet --out {shlex.quote(str(disk / 'run'))}")
        r = subprocess.run(["unshare", "--mount", "sh", "-c", script], capture_output=True, text=True)
        if "No space left on device" not in r.stderr:
            pytest.skip(f"no tmpfs in a mount namespace here: {r.stderr.strip()}")
        assert r.returncode == 3, r.stderr
        line = r.stderr.strip()
        assert len(r.stderr.splitlines()) == 1
        failed = line.removeprefix("budjam: error: ").split(": cannot")[0]
        assert failed.startswith(str(disk / "run") + "/"), line
