"""scripts/figures.py draws for print: units on the axes of dimensional quantities, ω* markers
that stand out of the spectrum, and colours from a colour-blind-safe palette. Checked on Fig. F1
drawn from a small hand-made table (two states of two runs)."""
import csv
import importlib.util
import json

import matplotlib.colors
import pytest

from conftest import SOURCE_DIR


@pytest.fixture(scope="module")
def figures():
    spec = importlib.util.spec_from_file_location("figures", SOURCE_DIR / "scripts" / "figures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def figF1(figures, tmp_path, monkeypatch):
    """Fig. F1 of two runs at P0 = 1e-4, each with the jammed state and one target: the Figure."""
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "analysis.json").write_text(json.dumps({
        "main_L": 8, "groups": [], "inputs": {"dos_files": 4, "moduli_files": 0},
        "main": {"dos": {"paper": {"through_origin_dZ": {"slope": 0.5}}}}}))
    columns = ["L", "P0", "run", "packing", "dphi", "omega_star", "dZ", "Z_minus_6", "N_u", "N_zero"]
    rows = []
    for k in range(2):
        run = tmp_path / f"run{k}"
        (run / "packings").mkdir(parents=True)
        for packing, dphi, omega_star in (("jammed", 0, 0.2), ("target_1", 1e-3, 0.5)):
            with open(run / "packings" / f"{packing}.dos.csv", "w") as f:
                f.write("lambda\n" + "".join(f"{(0.05 * (j + 1)) ** 2}\n" for j in range(40)))
            rows.append([8, "0.0001", run, packing, dphi, omega_star + 0.01 * k, 0.4 + dphi, 1.0, 3, 3])
    with open(tables / "dos.csv", "w", newline="") as f:
        csv.writer(f).writerows([columns, *rows])
    drawn = {}
    monkeypatch.setattr(figures, "save", lambda fig, out, name: drawn.setdefault(name, fig))
    T = figures.Tables(str(tables))
    T.out = str(tmp_path / "figures")
    figures.figF1(T)
    return drawn["figF1"]


def test_frequency_axes_carry_their_units(figF1):
    spectrum, omega_star, _ = figF1.axes
    assert "sqrt{k/m_0}" in spectrum.get_xlabel() and "sqrt{m_0/k}" in spectrum.get_ylabel()
    assert "sqrt{k/m_0}" in omega_star.get_ylabel()


def test_each_state_has_a_dashed_omega_star_line_across_the_panel_and_an_edged_marker(figF1, figures):
    spectrum = figF1.axes[0]
    dashed = [line for line in spectrum.get_lines() if line.get_linestyle() == "--" and len(line.get_xdata()) == 2
              and line.get_xdata()[0] == line.get_xdata()[1]]
    assert sorted(round(line.get_xdata()[0], 6) for line in dashed) == [0.205, 0.505]
    markers = [line for line in spectrum.get_lines() if line.get_marker() == "v"]
    assert len(markers) == 2
    for m in markers:
        assert m.get_markersize() >= 9 and matplotlib.colors.to_hex(m.get_markeredgecolor()) == "#000000"


def test_categorical_colours_are_okabe_ito_or_grey(figF1, figures):
    palette = {c.lower() for c in figures.OKABE_ITO}
    lines = figF1.axes[1].get_lines() + figF1.axes[2].get_lines()
    for line in lines:
        r, g, b = matplotlib.colors.to_rgb(line.get_color())
        assert matplotlib.colors.to_hex((r, g, b)) in palette or r == g == b, line.get_label()
    assert any(matplotlib.colors.to_hex(line.get_color()) in palette for line in lines)


def small_n_tables(tmp_path):
    """The quick reference's tables with every statistic from 3 samples: no SE, no interval."""
    import shutil
    tables = tmp_path / "few"
    shutil.copytree(SOURCE_DIR / "data" / "reference" / "quick" / "tables", tables)
    A = json.loads((tables / "analysis.json").read_text())

    def strip(o):
        if isinstance(o, dict):
            if "n" in o and ("se" in o or "ci95" in o):
                o.update(n=3, se=None)
                if "ci95" in o:
                    o["ci95"] = [None, None]
            for v in o.values():
                strip(v)
        elif isinstance(o, list):
            for v in o:
                strip(v)
    strip(A)
    (tables / "analysis.json").write_text(json.dumps(A))
    return tables


@pytest.mark.parametrize("name", ["fig2", "fig3", "figB1", "figD1", "figD2", "figE1"])
def test_groups_without_error_bars_draw_no_bars_and_no_traceback(figures, tmp_path, monkeypatch, name):
    drawn = {}
    monkeypatch.setattr(figures, "save", lambda fig, out, n: drawn.setdefault(n, fig))
    T = figures.Tables(str(small_n_tables(tmp_path)))
    T.out = str(tmp_path / "figures")
    figures.FIGURES[name](T)
    assert name in drawn


def test_a_missing_error_is_no_bar_not_a_zero_bar(figures):
    assert figures.err([None, None]) is None
    e = figures.err([0.1, None, float("nan")])
    assert e[0] == 0.1 and e[1] != e[1] and e[2] != e[2]
    lo, hi = figures.err([None, 0.2], [None, 0.3])
    assert lo[0] != lo[0] and hi[1] == 0.3


def test_a_figure_the_tables_cannot_give_is_an_error_or_with_record_not_drawn_a_reason(tmp_path):
    """figF1 from tables without spectra: exit 2 naming the stage; with --record-not-drawn (the
    pipeline's mode) exit 0, figF1.not-drawn holds the reason and an earlier figF1.png is gone."""
    import shutil
    import subprocess
    import sys
    tables = tmp_path / "tables"
    shutil.copytree(SOURCE_DIR / "data" / "reference" / "quick" / "tables", tables)
    A = json.loads((tables / "analysis.json").read_text())
    A["inputs"]["dos_files"] = 0
    (tables / "analysis.json").write_text(json.dumps(A))
    out = tmp_path / "figures"
    out.mkdir()
    (out / "figF1.png").write_bytes(b"an earlier grid's figure")
    command = [sys.executable, str(SOURCE_DIR / "scripts" / "figures.py"), "--tables", str(tables), "--out", str(out)]
    r = subprocess.run(command + ["figF1"], capture_output=True, text=True)
    assert r.returncode == 2 and "vibrational spectra" in r.stderr, r.stderr
    r = subprocess.run(command + ["--record-not-drawn", "figF1"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "not drawn" in r.stderr
    assert "vibrational spectra" in (out / "figF1.not-drawn").read_text()
    assert not (out / "figF1.png").exists()
