"""The Python module `budjam` against the command line on the same packings: the same library
functions must give the same numbers, and the arrays must describe the same physics."""
import json

import numpy as np
import pandas
import pytest

import budjam
from conftest import PACKING, SOURCE_DIR, rigidity_json


def test_write_reproduces_the_file_byte_for_byte(tmp_path):
    p = budjam.read_packing(PACKING)
    p.write(tmp_path / "copy.pack")
    assert (tmp_path / "copy.pack").read_bytes() == PACKING.read_bytes()


def test_packing_from_arrays_is_the_same_packing():
    p = budjam.read_packing(PACKING)
    q = budjam.Packing(L=p.L, x=p.x, y=p.y, theta=p.theta, b=p.b, gamma0=p.gamma0)
    for name in ("x", "y", "theta", "b", "gamma0"):
        np.testing.assert_array_equal(getattr(q, name), getattr(p, name))
    assert q.phi == p.phi and q.N == p.N
    np.testing.assert_array_equal(q.id, np.arange(p.N))
    np.testing.assert_array_equal(budjam.contacts(q)["force"], budjam.contacts(p)["force"])


def test_packing_from_arrays_is_checked_like_a_file():
    with pytest.raises(budjam.InputError, match=r"^L: must be finite and > 0 \(got -1\)$"):
        budjam.Packing(L=-1.0, x=[1.0], y=[1.0], theta=[0.0], b=[0.5], gamma0=[0.002])
    with pytest.raises(ValueError, match="length 1"):
        budjam.Packing(L=5.0, x=[1.0, 2.0], y=[1.0], theta=[0.0], b=[0.5])


def test_unreadable_packing_raises_input_error_naming_the_file(tmp_path):
    with pytest.raises(budjam.InputError, match="missing.pack"):
        budjam.read_packing(tmp_path / "missing.pack")


def test_lobes_are_tangent_dumbbells():
    p = budjam.read_packing(PACKING)
    lobes = p.lobes()
    np.testing.assert_array_equal(lobes["radius"][0::2], 0.5)
    np.testing.assert_array_equal(lobes["radius"][1::2], p.b / 2)
    d = np.hypot(lobes["x"][1::2] - lobes["x"][0::2], lobes["y"][1::2] - lobes["y"][0::2])
    np.testing.assert_allclose(d, (1 + p.b) / 2, rtol=1e-12)
    # The centroid is the area-weighted mean of the lobe centres.
    w_m, w_b = 1.0, p.b**2
    np.testing.assert_allclose((w_m * lobes["x"][0::2] + w_b * lobes["x"][1::2]) / (w_m + w_b), p.x, atol=1e-12)


@pytest.mark.parametrize("network", ["load-bearing", "raw"])
def test_rigidity_and_contacts_equal_budjam_rigidity(run_budjam, network):
    p = budjam.read_packing(PACKING)
    cli = json.loads(run_budjam("rigidity", PACKING, "--network", network, "--json").stdout)
    r, c = budjam.rigidity(p, network), budjam.contacts(p)
    assert len(c["force"]) == cli["contacts"]
    assert c["N_c"] // 2 == cli["contacts_load_bearing"]
    for key in ("N_nr", "N_f", "N_u", "N_u_buds"):
        assert c[key] == cli[key], key
    for key in ("cells", "joints", "independent_bars", "redundant_bars", "free_pebbles", "spans_x", "spans_y",
                "buds_rigid"):
        assert r[key] == cli[key], key
    assert len(r["bar_lobes"]) == cli["bars"] == r["bars"]
    assert len(r["cluster_cells"]) == cli["rigid_clusters"]["count"]
    # Labels: the cells of the largest cluster are those labelled with it.
    cluster = r["table"]["cluster"]
    assert int(np.sum(cluster == r["largest_cluster"])) == r["rigid_clusters"]["largest_cells"]
    assert r["cluster_cells"][r["largest_cluster"]] == r["rigid_clusters"]["largest_cells"]
    np.testing.assert_array_equal(r["lobe_cluster"], np.repeat(cluster, 2))


@pytest.mark.slow
def test_moduli_equal_budjam_moduli(run_budjam, relaxed):
    cli = json.loads(run_budjam("moduli", relaxed, "--json").stdout)
    m = budjam.moduli(budjam.read_packing(relaxed))
    assert m["energy_minimum"] and cli["energy_minimum"]
    assert m == {k: v for k, v in cli.items() if k != "file"}
    # G(0) of the shear-stability scan is Lees–Edwards shear: E_xyxy of the energy stiffness.
    E = np.array(m["response"]["E"])
    assert E.shape == (4, 4) and m["shear_stability"]["G_min"] <= E[1, 1] <= m["shear_stability"]["G_max"]


@pytest.mark.slow
def test_spectrum_equals_budjam_dos_and_modes_are_orthonormal_and_free_of_translations(run_budjam, relaxed):
    run_budjam("dos", relaxed, "--quiet", "--out", relaxed.with_suffix(".dos"))
    cli = json.loads(relaxed.with_suffix(".dos.json").read_text())
    table = pandas.read_csv(relaxed.with_suffix(".dos.csv"), float_precision="round_trip")
    s = budjam.spectrum(budjam.read_packing(relaxed))
    assert s["N_zero"] == cli["N_zero"] and s["omega_star"] == cli["omega_star"]
    np.testing.assert_array_equal(s["table"]["lambda"], table["lambda"])
    np.testing.assert_array_equal(s["table"]["participation"], table["participation"])
    m = np.concatenate([s["mass"][3 * int(c) : 3 * int(c) + 3] for c in s["cells"]])
    v = s["eigenvectors"]
    assert v.shape == (3 * len(s["cells"]), len(s["table"]["lambda"]))
    np.testing.assert_allclose(v.T @ v, np.eye(v.shape[1]), atol=1e-10)
    # Mass-weighted modes e = M^(1/2) u are orthogonal to M^(1/2) t of the uniform translations t.
    for axis in (0, 1):
        t = np.zeros(len(m))
        t[axis::3] = 1.0
        np.testing.assert_allclose(v.T @ (np.sqrt(m) * t), 0.0, atol=1e-9)


def test_particle_frame_is_what_export_writes(run_budjam, tmp_path):
    import ase.io

    run_budjam("export", PACKING, "--format", "xyz", "--out", tmp_path / "p")
    atoms = ase.io.read(tmp_path / "p.xyz", format="extxyz")
    f = budjam.particle_frame(budjam.read_packing(PACKING))
    np.testing.assert_array_equal(atoms.positions[:, 0], f["wrapped_x"])
    np.testing.assert_array_equal(atoms.arrays["rigid_cluster"], f["rigid_cluster"])
    budjam.export(budjam.read_packing(PACKING), tmp_path / "q.xyz", "xyz")
    assert (tmp_path / "q.xyz").read_bytes() == (tmp_path / "p.xyz").read_bytes()


@pytest.mark.slow
def test_load_run_gives_every_table_as_a_dataframe(run_dir):
    run = budjam.load_run(run_dir)
    assert run.summary == json.loads((run_dir / "summary.json").read_text())
    stems = sorted(csv.stem for csv in run_dir.glob("*.csv"))
    assert sorted(run.tables) == stems and {"steps", "divisions", "bud_events", "moduli"} <= set(stems)
    for stem in stems:
        lines = (run_dir / f"{stem}.csv").read_text().splitlines()
        assert list(run.tables[stem].columns) == lines[0].split(",")
        assert len(run.tables[stem]) == len(lines) - 1
    assert run.steps is run.tables["steps"]
    assert [p.name for p in run.packings] == sorted(p.name for p in (run_dir / "packings").glob("*.pack"))
    with pytest.raises(AttributeError, match="no table"):
        run.nonexistent


def test_trials_csv_reads_back_with_pandas_and_its_accepted_trials_are_the_accepted_steps(run_dir):
    trials = pandas.read_csv(run_dir / "trials.csv", float_precision="round_trip")
    steps = pandas.read_csv(run_dir / "steps.csv", float_precision="round_trip")
    summary = json.loads((run_dir / "summary.json").read_text())
    accepted = trials[trials["verdict"] == "accepted"]
    assert len(accepted) == len(steps) - 1 == summary["accepted_steps"]
    np.testing.assert_array_equal(accepted["phi"].to_numpy(), steps["phi"].to_numpy()[1:])
    np.testing.assert_array_equal(accepted["E_per_cell"].to_numpy(), steps["E_per_cell"].to_numpy()[1:])
    np.testing.assert_array_equal(accepted["attempt"].to_numpy(), steps["attempts"].to_numpy()[1:])
    # Each attempt once, in order (a settle repeats the attempt it relaxes on).
    first = trials[trials["start"] != "settled"]["attempt"].to_numpy()
    np.testing.assert_array_equal(first, np.arange(1, len(first) + 1))
    verdicts = trials["verdict"].value_counts()
    settles = (trials["start"] == "settled").sum()  # each turns a rejected attempt into an accepted one
    assert verdicts.get("rejected", 0) + verdicts.get("below_window", 0) - settles == summary["rejected_steps"]
    # The costs of the trials and of the initial relaxation (of two cells) are the run's.
    assert 0 < summary["force_evaluations"] - trials["evaluations"].sum() < 10
    # The jamming table: a rejected trial is above the window, a lower end of the bracket below it.
    assert (trials[trials["verdict"] == "rejected"]["E_per_cell"] > 2e-16).all()
    assert (trials[trials["verdict"] == "below_window"]["E_per_cell"] < 1e-16).all()


def test_load_run_refuses_an_unfinished_run(tmp_path):
    with pytest.raises(budjam.InputError, match="no summary.json"):
        budjam.load_run(tmp_path)


@pytest.mark.slow
def test_grow_generator_follows_the_same_run_as_budjam_grow(run_dir):
    events = list(budjam.grow(SOURCE_DIR / "data" / "scenes" / "demo.toml"))
    run = budjam.load_run(run_dir)
    kinds = [e["kind"] for e in events]
    assert kinds[-1] == "finished" == run.summary["status"]
    # One jamming per episode (a run that unjams jams again); the run's jamming point is the last.
    jammings = [e for e in events if e["kind"] == "jammed"]
    assert len(jammings) == 1 + len(run.summary["unjammings"])
    assert jammings[-1]["phi_J"] == jammings[-1]["phi"] == run.summary["phi_J"]
    if run.summary["phi_2"] is not None:
        assert [e["phi_2"] for e in events if e["kind"] == "phi2"][-1] == run.summary["phi_2"]
    assert kinds.count("division") == len(run.divisions)
    assert sum(k.startswith("bud_") for k in kinds) == len(run.bud_events)
    # The demo scene's two targets, after those of episodes an unjamming discarded.
    targets = [e for e in events if e["kind"] == "target"]
    lost = sum(u["targets_lost"] for u in run.summary["unjammings"])
    assert len(targets) == 2 + lost
    for t in targets[lost:]:
        saved = budjam.read_packing(run_dir / "packings" / f"target_{t['index']}.pack")
        for name in ("x", "y", "theta", "b", "gamma0", "id", "parent"):
            np.testing.assert_array_equal(getattr(t["packing"], name), getattr(saved, name))
        # The event's packing carries the saved file's metadata, so the bridges see its step.
        assert t["packing"].meta == saved.meta
        assert t["packing"].to_ase().info["step"] == t["step"] == saved.meta["step"]
    jammed = budjam.read_packing(run_dir / "packings" / "jammed.pack")
    assert jammings[-1]["packing"].meta == jammed.meta


def test_grow_refuses_a_seed_a_scene_file_cannot_hold_as_budjam_grow_does():
    scene = SOURCE_DIR / "data" / "scenes" / "demo.toml"
    for seed in (2**63, 2**64, -1):
        with pytest.raises(budjam.InputError, match="run.seed: must be ≥ 0 and below 2\\^63") as refused:
            budjam.grow(scene, seed=seed)
        assert "\n" not in str(refused.value)
    budjam.grow(scene, seed=2**63 - 1)  # the largest is fine
    budjam.grow(scene, seed=np.int64(3))  # an integer of numpy's is an integer


def test_grow_refuses_what_is_not_a_scene_path_or_a_seed_in_one_line():
    for scene, seed, field in ((None, None, "scene"), (3, None, "scene"),
                               (SOURCE_DIR / "data" / "scenes" / "demo.toml", 1.5, "seed"),
                               (SOURCE_DIR / "data" / "scenes" / "demo.toml", True, "seed")):
        with pytest.raises(TypeError, match=f"^{field}: ") as refused:
            budjam.grow(scene, seed=seed)
        assert "\n" not in str(refused.value)


def test_spectrum_refuses_a_negative_mode_count_as_budjam_dos_does():
    with pytest.raises(budjam.InputError, match="modes: must be"):
        budjam.spectrum(budjam.read_packing(PACKING), method="arpack", modes=-3)


@pytest.mark.slow
def test_grow_reports_an_early_stop_as_an_event_not_an_exception():
    events = []
    status = budjam.grow(SOURCE_DIR / "data" / "scenes" / "demo.toml", set=["growth.max_steps=50"],
                         callback=events.append)
    assert status == "step_limit"
    assert events[-1]["kind"] == "stopped" and events[-1]["status"] == "step_limit"


@pytest.mark.slow
def test_survival_equals_budjam_survival(run_dir, run_budjam, tmp_path):
    run_budjam("survival", run_dir, "--out", tmp_path / "s", "--quiet")
    summary = json.loads((tmp_path / "s.json").read_text())
    table = pandas.read_csv(tmp_path / "s.csv", float_precision="round_trip")
    s = budjam.survival([run_dir])
    assert s["records"] == summary["records"] and s["events"] == summary["events"]
    curve = s["table"]
    for column in ("a", "S", "se", "at_risk", "events", "censored"):
        np.testing.assert_array_equal(curve[column], table[column])
    assert np.all(np.diff(curve["S"]) <= 0)  # a survival curve never rises


def test_spectrum_of_a_saddle_is_flagged_and_its_unstable_mode_is_found_by_the_moduli_test():
    p = budjam.read_packing(PACKING)
    s = budjam.spectrum(p, method="dense")
    m = budjam.moduli(p)
    assert s["energy_minimum"] is False and m["energy_minimum"] is False
    assert s["stationary_point"] == m["stationary_point"] == "saddle"
    assert s["unstable_modes"] == m["kernel"]["unstable_modes"] >= 1
    # No λ at or below −lambda_tol is called quasi-zero.
    lam, qz = s["table"]["lambda"], s["table"]["quasi_zero"]
    assert all(not z for l, z in zip(lam, qz) if l <= -s["lambda_tol"])


def test_a_minimum_held_by_a_pair_at_zero_force_is_flagged_as_such_by_moduli_and_spectrum():
    p = budjam.read_packing(PACKING.parent / "contact_bounded_jamming_L20_seed3.pack")
    m, s = budjam.moduli(p), budjam.spectrum(p, method="dense")
    assert m["energy_minimum"] is True and s["energy_minimum"] is True
    assert m["stationary_point"] == s["stationary_point"] == "contact-bounded minimum"
    assert m["B"] is None and m["moduli_affine"]["B"] > 0  # no relaxed response
