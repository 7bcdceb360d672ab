"""What `budjam` says on stderr: the progress line of a growth run, an expected stop as a notice
that agrees with the exit code, and parse errors that point to the help of the subcommand used."""
import re

from conftest import SOURCE_DIR

DEMO = SOURCE_DIR / "data" / "scenes" / "demo.toml"


def test_progress_lines_show_phi_the_heading_a_nonzero_rate_and_the_run_directory(run_budjam, tmp_path):
    out = tmp_path / "demo"
    r = run_budjam("grow", DEMO, "--out", out)
    lines = [line for line in r.stderr.splitlines() if line.startswith("grow: ")]
    assert lines and len(lines) == len(r.stderr.splitlines())
    pattern = re.compile(r"phi \d\.\d{8}  (toward phi_J(\+\S+)?|toward phi_2|at the last target)  N \d+ .* "
                         r"(\d+\.\d) steps/s  -> (.*)$")
    for line in lines:
        match = pattern.search(line)
        assert match, line
        assert match.group(4) == str(out)
    events = [line for line in lines if line.startswith(("grow: jammed:", "grow: target", "grow: finished:"))]
    assert len(events) >= 3
    for line in events:  # events follow growth steps: their rate is measured, never 0.0
        assert float(pattern.search(line).group(3)) > 0, line
    assert "toward phi_J+0.001" in next(line for line in lines if line.startswith("grow: jammed:"))
    # a target landed on is behind the run: the line names the next one
    assert "toward phi_J+0.01 " in next(line for line in lines if line.startswith("grow: target dphi=0.001:"))


def test_a_step_limit_stop_is_a_notice_and_exit_0_never_failed(run_budjam, tmp_path):
    r = run_budjam("grow", DEMO, "--out", tmp_path / "limited", "--set", "growth.max_steps=40", check=False)
    assert r.returncode == 0
    assert "FAILED" not in r.stderr and "error" not in r.stderr
    assert "grow: stopped (step_limit)" in r.stderr
    assert r.stderr.splitlines()[-1].startswith("budjam: grow: run stopped at the step limit")


def test_a_parse_error_names_the_help_of_the_subcommand_used(run_budjam):
    r = run_budjam("grow", DEMO, "--no-such-option", check=False)
    assert r.returncode == 2 and r.stderr.rstrip().endswith("(see budjam grow --help)")
    r = run_budjam("moduli", check=False)
    assert r.returncode == 2 and r.stderr.rstrip().endswith("(see budjam moduli --help)")
    r = run_budjam("--no-such-option", check=False)
    assert r.returncode == 2 and r.stderr.rstrip().endswith("(see budjam --help)")
