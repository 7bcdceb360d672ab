"""`budjam export` read back by independent readers: ASE (extended XYZ), gsd (HOOMD schema) and
meshio (legacy VTK). The three files of one packing must describe the same particles and bonds,
and agree with `budjam rigidity` on the same packing."""
import collections
import re
import subprocess

import ase.io
import gsd.hoomd
import meshio
import numpy as np
import pytest

from conftest import PACKING, assert_gsd_frames_are_the_xyz_frames, rigidity_json


# The independent reader of each format.
READERS = {
    "xyz": lambda path: ase.io.read(path, format="extxyz"),
    "gsd": lambda path: gsd.hoomd.open(path, "rb")[0],
    "vtk": meshio.read,
}


def export_formats(run_budjam):
    """The formats `budjam export --format` accepts, as its help lists them ({xyz,gsd,vtk})."""
    help_text = run_budjam("export", "--help").stdout
    return re.search(r"--format\s+\S*\{([^}]*)\}", help_text).group(1).split(",")


def test_every_export_format_has_a_reader_here(run_budjam):
    assert sorted(export_formats(run_budjam)) == sorted(READERS)


@pytest.fixture(scope="module", params=["unsheared", "sheared"])
def exported(request, run_budjam, sheared_packing, tmp_path_factory):
    packing = PACKING if request.param == "unsheared" else sheared_packing
    base = tmp_path_factory.mktemp("export") / "p"
    files = {"packing": packing}
    for fmt, read in READERS.items():
        run_budjam("export", packing, "--format", fmt, "--out", base)
        files[fmt] = read(str(base) + "." + fmt)
    return files


def header(packing):
    fields = dict(line.split(" ", 1) for line in packing.read_text().splitlines()[1:5])
    return int(fields["N"]), float(fields["L"]), float(fields["shear"])


def bud_diameters(packing):
    lines = packing.read_text().splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith("cells "))
    columns = lines[start].split()[1:]
    rows = [line.split() for line in lines[start + 1 : lines.index("end")]]
    return np.array([float(row[columns.index("b")]) for row in rows])


def vtk_points(exported, name):
    return exported["vtk"].point_data[name].ravel()


def vtk_bonds(exported, name):
    return exported["vtk"].cell_data[name][0].ravel()


def test_one_particle_per_lobe_in_every_format(exported):
    n, _, _ = header(exported["packing"])
    assert len(exported["xyz"]) == 2 * n
    assert exported["gsd"].particles.N == 2 * n
    assert exported["vtk"].points.shape == (2 * n, 3)
    kinds = np.where(np.arange(2 * n) % 2 == 0, "mother", "bud")
    assert list(exported["xyz"].arrays["type"]) == list(kinds)
    g = exported["gsd"].particles
    assert [g.types[t] for t in g.typeid] == list(kinds)
    assert list(vtk_points(exported, "bud")) == list(np.arange(2 * n) % 2)
    np.testing.assert_array_equal(exported["xyz"].arrays["cell_id"], np.arange(2 * n) // 2)


# A per-lobe quantity as each format's reader holds it (a format without an entry fails the test below).
PER_LOBE = {
    "xyz": lambda exported, name: exported["xyz"].arrays[name],
    "gsd": lambda exported, name: exported["gsd"].log["particles/" + name],
    "vtk": vtk_points,
}


def test_every_per_lobe_quantity_has_one_name_and_the_same_values_in_every_format(exported):
    # The XYZ columns after type, pos and radius are the per-lobe quantities.
    names = [name for name in exported["xyz"].arrays if name not in ("numbers", "positions", "type", "radius")]
    assert names == ["cell_id", "id", "rigid_cluster", "rattler"]
    assert sorted(PER_LOBE) == sorted(READERS)
    for name in names:
        xyz = exported["xyz"].arrays[name].astype(np.int64)
        for fmt, values in PER_LOBE.items():
            np.testing.assert_array_equal(np.asarray(values(exported, name)).ravel(), xyz, err_msg=f"{fmt}: {name}")


def test_box_is_the_packing_box(exported):
    _, L, shear = header(exported["packing"])
    np.testing.assert_allclose(exported["xyz"].cell[:], [[L, 0, 0], [shear * L, L, 0], [0, 0, 1]])
    assert list(exported["xyz"].pbc) == [True, True, False]
    assert exported["gsd"].configuration.dimensions == 2
    np.testing.assert_allclose(exported["gsd"].configuration.box, [L, L, 1, shear, 0, 0])


def test_positions_agree_modulo_the_box(exported):
    _, L, shear = header(exported["packing"])
    a1, a2 = np.array([L, 0.0]), np.array([shear * L, L])
    wrapped = exported["xyz"].positions[:, :2]
    # GSD: HOOMD centres the box on the origin; float32 positions.
    g = exported["gsd"].particles
    np.testing.assert_allclose(g.position[:, :2] + 0.5 * (a1 + a2), wrapped, atol=1e-5)
    # VTK: unwrapped (cells whole) = wrapped + image in box vectors, the image from GSD.
    unwrapped = wrapped + g.image[:, :1] * a1 + g.image[:, 1:2] * a2
    np.testing.assert_allclose(exported["vtk"].points[:, :2], unwrapped, atol=1e-9)
    # Wrapped positions lie in the (sheared) box.
    frac = np.linalg.solve(np.array([a1, a2]).T, wrapped.T).T
    assert frac.min() > -1e-9 and frac.max() < 1 + 1e-9


def test_radii_are_the_lobe_radii(exported):
    r = exported["xyz"].arrays["radius"]
    assert np.all(r[0::2] == 0.5)  # mothers: D0 = 1
    np.testing.assert_array_equal(r[1::2], 0.5 * bud_diameters(exported["packing"]))
    np.testing.assert_allclose(exported["gsd"].particles.diameter, 2 * r, rtol=1e-6)
    np.testing.assert_array_equal(vtk_points(exported, "radius"), r)


def test_bonds_are_links_then_contacts_with_the_same_forces(exported):
    n, _, _ = header(exported["packing"])
    g = exported["gsd"]
    lines = exported["vtk"].cells_dict["line"]
    assert g.bonds.N == len(lines) > n
    np.testing.assert_array_equal(g.bonds.group, lines)
    np.testing.assert_array_equal(g.bonds.group[:n], np.column_stack([2 * np.arange(n), 2 * np.arange(n) + 1]))
    kind = np.asarray(g.bonds.typeid)
    assert [g.bonds.types[k] for k in kind[:n]] == ["link"] * n
    assert set(kind[n:]) == {1}
    np.testing.assert_array_equal(vtk_bonds(exported, "contact"), kind)
    force = g.log["bonds/force"]
    np.testing.assert_array_equal(vtk_bonds(exported, "force"), force)
    assert np.all(force[n:] > 0)  # contacts are repulsive overlaps


def test_contacts_and_clusters_agree_with_budjam_rigidity(exported, run_budjam):
    n, _, _ = header(exported["packing"])
    rigidity = rigidity_json(run_budjam, exported["packing"])
    kind = np.asarray(exported["gsd"].bonds.typeid)
    assert int(np.sum(kind == 1)) == rigidity["contacts"]
    cluster = exported["xyz"].arrays["rigid_cluster"]
    assert np.all(cluster[0::2] == cluster[1::2])  # a cell's lobes share its bar's cluster
    cells_per_cluster = collections.Counter(cluster[0::2][cluster[0::2] >= 0])
    assert max(cells_per_cluster.values()) == rigidity["rigid_clusters"]["largest_cells"]
    rattler = exported["xyz"].arrays["rattler"]
    assert int(np.sum(rattler[0::2])) == rigidity["N_f"]
    assert np.all((cluster < 0) == rattler)  # the load-bearing network: rattlers are not analysed


def test_bad_format_and_missing_packing_are_input_errors(run_budjam, tmp_path):
    r = run_budjam("export", PACKING, "--format", "pdb", "--out", tmp_path / "x", check=False)
    assert r.returncode == 2
    r = run_budjam("export", tmp_path / "none.pack", "--format", "xyz", check=False)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "none.pack" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_gsd_without_its_writer_is_an_output_error_leaving_nothing(budjam_exe, tmp_path):
    env = {"BUDJAM_PYTHON": str(tmp_path / "no-python")}
    r = subprocess.run([budjam_exe, "export", PACKING, "--format", "gsd", "--out", tmp_path / "p"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 3
    assert r.stderr.count("\n") == 1 and "python3-gsd" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_trajectory_exports_to_one_gsd_file_with_every_frame(run_budjam, sheared_packing, tmp_path):
    """Two frames (unsheared, then sheared) as a run's trajectory.xyz holds them, converted by
    `budjam export trajectory.xyz --format gsd`, written beside it by default."""
    for name, packing in (("a", PACKING), ("b", sheared_packing)):
        run_budjam("export", packing, "--format", "xyz", "--out", tmp_path / name)
    trajectory = tmp_path / "trajectory.xyz"
    trajectory.write_bytes((tmp_path / "a.xyz").read_bytes() + (tmp_path / "b.xyz").read_bytes())
    run_budjam("export", trajectory, "--format", "gsd")
    assert assert_gsd_frames_are_the_xyz_frames(tmp_path / "trajectory.gsd", trajectory) == 2


@pytest.mark.parametrize("damage, args, message", [
    (lambda text: text[: text.index("\n", text.index("\n", text.index("mother")) + 1)], (),
     r"trajectory\.xyz:5: the file ends inside a frame"),
    (lambda text: text.replace("mother", "bud", 1), (), r"trajectory\.xyz:3: type: lobe 0 is a mother"),
    (lambda text: re.sub(r"step=\d+", "step=x", text), (), r"trajectory\.xyz:2: step: not a non-negative integer"),
    (lambda text: text, ("--network", "raw"), r"--network: a trajectory's frames keep"),
])
def test_a_trajectory_budjam_did_not_write_is_refused_and_nothing_is_written(run_budjam, tmp_path, damage, args,
                                                                              message):
    run_budjam("export", PACKING, "--format", "xyz", "--out", tmp_path / "trajectory")
    trajectory = tmp_path / "trajectory.xyz"
    trajectory.write_text(damage(trajectory.read_text()))
    (tmp_path / "trajectory.gsd").write_bytes(b"earlier")
    r = run_budjam("export", trajectory, "--format", "gsd", *args, check=False)
    assert r.returncode == 2 and re.search(message, r.stderr) and len(r.stderr.splitlines()) == 1, r.stderr
    assert (tmp_path / "trajectory.gsd").read_bytes() == b"earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trajectory.gsd", "trajectory.xyz"]


def test_a_trajectory_exports_to_gsd_only(run_budjam, tmp_path):
    run_budjam("export", PACKING, "--format", "xyz", "--out", tmp_path / "trajectory")
    r = run_budjam("export", tmp_path / "trajectory.xyz", "--format", "vtk", check=False)
    assert r.returncode == 2 and "exports to gsd only" in r.stderr


def test_a_packing_named_xyz_is_read_as_a_packing_and_never_replaced_by_its_export(run_budjam, tmp_path):
    """What a file is follows its first line, not its name: a packing called p.xyz exports as a
    packing, and its default output p.xyz (the input itself) is refused, the input unchanged."""
    packing = tmp_path / "p.xyz"
    packing.write_bytes(open(PACKING, "rb").read())
    run_budjam("export", packing, "--format", "vtk")
    run_budjam("export", PACKING, "--format", "vtk", "--out", tmp_path / "q")
    assert (tmp_path / "p.vtk").read_bytes() == (tmp_path / "q.vtk").read_bytes()
    r = run_budjam("export", packing, "--format", "xyz", check=False)
    assert r.returncode == 2 and "is the input file" in r.stderr and len(r.stderr.splitlines()) == 1
    assert packing.read_bytes() == open(PACKING, "rb").read()
