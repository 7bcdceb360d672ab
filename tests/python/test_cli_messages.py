"""What `budjam` says on stderr: the progress line of a growth run, an expected stop as a notice
that agrees with the exit code, and parse errors that point to the help of the subcommand used."""
import json
import re

import pytest

from conftest import PACKING, SOURCE_DIR

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
    # a mistyped option of budjam's own is named, before a command or without one
    for args in (["--versio"], ["--foo", "grow", DEMO]):
        r = run_budjam(*args, check=False)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
        assert f"unknown option '{args[0]}'" in r.stderr and r.stderr.rstrip().endswith("(see budjam --help)")


def test_a_mistyped_command_is_named_with_the_commands_there_are(run_budjam):
    r = run_budjam("gorw", DEMO, check=False)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "unknown command 'gorw'" in r.stderr and "grow" in r.stderr and "moduli" in r.stderr
    # no command at all is still the parser's own message
    r = run_budjam(check=False)
    assert r.returncode == 2 and "unknown command" not in r.stderr


def test_a_value_out_of_range_from_set_is_blamed_on_the_set_not_the_file(run_budjam, tmp_path):
    r = run_budjam("grow", DEMO, "--out", tmp_path / "r", "--set", "growth.P0=-1", check=False)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "--set growth.P0=-1: growth.P0: must be at least 1e-300" in r.stderr and "demo.toml" not in r.stderr
    # the last --set of a key is the one blamed
    r = run_budjam("grow", DEMO, "--out", tmp_path / "r", "--set", "growth.dt=1", "--set", "growth.dt=0", check=False)
    assert "--set growth.dt=0: growth.dt:" in r.stderr
    assert not (tmp_path / "r").exists()
    # a rule the file's own value breaks names the file
    bad = tmp_path / "bad.toml"
    bad.write_text("[growth]\ndt = 0\n")
    r = run_budjam("grow", bad, "--out", tmp_path / "r", "--set", "growth.P0=1e-3", check=False)
    assert r.returncode == 2 and f"{bad}: growth.dt:" in r.stderr and "--set" not in r.stderr


@pytest.mark.parametrize("args", [
    ["grow", DEMO, "--out", ""], ["moduli", PACKING, "--out", ""], ["dos", PACKING, "--out", " "],
    ["rigidity", PACKING, "--out", ""], ["export", PACKING, "--format", "xyz", "--out", ""],
    ["render", PACKING, "-o", ""], ["analyse", SOURCE_DIR / "data", "--out", ""],
], ids=["grow", "moduli", "dos", "rigidity", "export", "render", "analyse"])
def test_an_empty_output_name_is_refused_not_read_as_not_given(run_budjam, tmp_path, args):
    r = run_budjam(*args, check=False, cwd=tmp_path)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "an empty name names no file or directory" in r.stderr
    assert not any(tmp_path.iterdir())


def test_no_other_command_writes_into_the_top_level_of_a_run_directory(run_budjam, tmp_path):
    run = tmp_path / "run"
    run_budjam("grow", DEMO, "--out", run, "--quiet")
    before = {p: p.read_bytes() for p in run.rglob("*") if p.is_file()}
    pack = run / "packings" / "jammed.pack"
    for args in (["moduli", pack, "--out", run / "summary"], ["survival", run, "-o", run / "bud_events.csv"],
                 ["analyse", run, "--out", run], ["render", pack, "-o", run / "jammed.svg"],
                 ["export", pack, "--format", "xyz", "--out", run / "steps"]):
        r = run_budjam(*args, check=False)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (args, r.stderr)
        assert "is a budjam run directory" in r.stderr, (args, r.stderr)
    assert {p: p.read_bytes() for p in run.rglob("*") if p.is_file()} == before
    # beside the packings, where the moduli and spectra of a run go, is fine
    run_budjam("moduli", pack, "--out", run / "packings" / "jammed.moduli", "--quiet")


def test_a_path_with_control_bytes_is_printed_escaped_on_every_line(run_budjam, run_dir, tmp_path):
    """A newline in --out never splits a progress line, a step-limit notice, or the closing line of analyse
    and accuracy: it is printed as \\x0a, as every other message prints it."""
    runs = {
        "grow": ["grow", DEMO, "--out", tmp_path / "g\nh"],
        "step_limit": ["grow", DEMO, "--out", tmp_path / "s\nt", "--set", "growth.max_steps=40"],
        "analyse": ["analyse", run_dir, "--out", tmp_path / "a\nb"],
        "accuracy": ["accuracy", "--packings", f"x={run_dir}", "--out", tmp_path / "acc\nx"],
    }
    for what, args in runs.items():
        r = run_budjam(*args)
        assert r.stderr, what
        for line in r.stderr.splitlines():
            assert line.startswith(("grow: ", "budjam: ", "analyse: ", "accuracy: ")), (what, line)
        assert "\\x0a" in r.stderr, (what, r.stderr)


def doc_key_tree(text):
    """The keys of a JSON document as docs/spectrum.md lists them: `a, b{c, d}, e{...} | null`; a brace of
    `name: value` is a map of any keys (None)."""
    text = re.sub(r"\s*\|\s*null", "", text)
    pos = 0

    def keys():
        nonlocal pos
        out = {}
        while pos < len(text) and text[pos] != "}":
            name = re.match(r"\s*([^,{}\s]+)\s*", text[pos:])
            assert name, text[pos:pos + 40]
            pos += name.end()
            sub = None
            if pos < len(text) and text[pos] == "{":
                pos += 1
                start = pos
                sub = keys()
                if ":" in text[start:pos]:
                    sub = None
                pos += 1  # the closing brace
            out[name.group(1).rstrip(":")] = sub
            rest = re.match(r"\s*,?\s*", text[pos:])
            pos += rest.end()
        return out

    return keys()


def assert_keys_as_documented(document, doc, where):
    assert set(document) == set(doc), f"{where}: missing {set(document) - set(doc)}, stale {set(doc) - set(document)}"
    for key, sub in doc.items():
        if sub is not None and isinstance(document[key], dict):
            assert_keys_as_documented(document[key], sub, f"{where}.{key}")


def test_the_dos_json_has_exactly_the_keys_docs_spectrum_lists(run_budjam):
    page = (SOURCE_DIR / "docs" / "spectrum.md").read_text()
    listed = re.search(r"JSON\s+keys: `([^`]*)`", page)
    assert listed, "docs/spectrum.md: no JSON key list"
    document = json.loads(run_budjam("dos", SOURCE_DIR / "tests" / "data" / "negative_G_target_L8.pack",
                                     "--json").stdout)
    assert_keys_as_documented(document, doc_key_tree(listed.group(1)), "dos")
