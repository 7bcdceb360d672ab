"""`budjam render -o FILE.png|FILE.pdf` converts directly (rsvg-convert) and leaves only FILE."""
import shutil

import pytest

from conftest import PACKING

pytestmark = pytest.mark.skipif(shutil.which("rsvg-convert") is None, reason="needs librsvg2-bin")


@pytest.mark.parametrize("ext,magic", [("png", b"\x89PNG\r\n\x1a\n"), ("pdf", b"%PDF-")])
def test_png_and_pdf_are_written_directly_and_alone(run_budjam, tmp_path, ext, magic):
    out = tmp_path / f"packing.{ext}"
    run_budjam("render", PACKING, "-o", out)
    assert out.read_bytes().startswith(magic)
    assert list(tmp_path.iterdir()) == [out]


def test_another_extension_is_an_input_error(run_budjam, tmp_path):
    r = run_budjam("render", PACKING, "-o", tmp_path / "packing.jpg", check=False)
    assert r.returncode == 2 and "packing.jpg" in r.stderr
    assert list(tmp_path.iterdir()) == []
