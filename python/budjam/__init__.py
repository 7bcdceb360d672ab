"""budjam: growing budding-cell packings, jamming and rigidity, from Python.

Units throughout: lengths in mother diameters D0 = 1, forces in k*D0 (spring constant k = 1),
stresses, pressures and 2D moduli in k, eigenvalues in k/m (m = mother mass), angles in radians,
time in the units of the growth rates (docs/files.md lists every file's columns and units).

    import budjam
    p = budjam.read_packing("run/packings/jammed.pack")
    p.x, p.y, p.theta, p.b                 # numpy arrays, one entry per cell
    p.lobes()["radius"]                    # lobe 2i: mother of cell i, 2i+1: its bud
    budjam.rigidity(p)["lobe_cluster"]     # rigid cluster of every lobe
    budjam.moduli(p)["G"]                  # shear modulus (contact-virial convention)
    budjam.export(p, "jammed.gsd", "gsd")  # for OVITO / HOOMD-blue
    budjam.survival(["run"])["S"]          # Kaplan-Meier S(a) of the buds free at jamming
    run = budjam.load_run("run")           # pandas DataFrames of every table of a growth run
    run.steps["phi"]
    for event in budjam.grow("scene.toml", seed=3):   # jamming, targets, phi_2, divisions, buds
        print(event["kind"], event["phi"])

The functions are the ones `budjam` (the command line) runs, so their results are the same.
"""
import json
import pathlib

from ._budjam import (Growth, InputError, NoResultError, OutputError, Packing, _one_line, contacts, export, moduli,
                      particle_frame, read_packing, rigidity, spectrum, survival)

__all__ = ["Growth", "grow", "InputError", "NoResultError", "OutputError", "Packing", "Run", "contacts", "export",
           "load_run", "moduli", "particle_frame", "read_packing", "rigidity", "spectrum", "survival"]


def _input_error(message):
    """InputError with the message as the command line prints it: one line, control bytes escaped."""
    return InputError(_one_line(message))


def _read_table(path, pandas):
    try:
        return pandas.read_csv(path, float_precision="round_trip", encoding="utf-8")
    except (ValueError, OSError) as e:  # pandas' ParserError and EmptyDataError, UnicodeDecodeError are ValueErrors
        raise _input_error(f"{path}: not a readable CSV table: {e}") from None


class Run:
    """A finished growth-run directory (`budjam grow`): summary.json as a dict and every CSV table
    of the directory as a pandas DataFrame, by file stem: run.steps, run.divisions, run.bud_events,
    run.moduli, run.dos, run.rigidity_events, run.trials (those the scene asked for). Empty fields
    (e.g. a P0 of "no feedback", a quantity not reached) are NaN; numbers are read back
    bit-identically (float_precision="round_trip"). Packing files are listed in run.packings."""

    def __init__(self, directory):
        import pandas

        self.dir = pathlib.Path(directory)
        summary = self.dir / "summary.json"
        if not summary.is_file():
            raise _input_error(f"{self.dir}: not a finished run (no summary.json)")
        try:
            with open(summary, encoding="utf-8") as f:
                self.summary = json.load(f)
        except (ValueError, OSError) as e:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
            raise _input_error(f"{summary}: invalid JSON: {e}") from None
        if not isinstance(self.summary, dict) or self.summary.get("format") != "budjam-summary":
            raise _input_error(f"{summary}: not a budjam run summary (a JSON object with format budjam-summary)")
        packings = self.dir / "packings"
        if packings.exists() and not packings.is_dir():
            raise _input_error(f"{packings}: not a directory (a run keeps its packings in one)")
        self.tables = {csv.stem: _read_table(csv, pandas) for csv in sorted(self.dir.glob("*.csv"))}
        self.packings = sorted(packings.glob("*.pack"))

    def __getattr__(self, name):
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return tables[name]
        raise AttributeError(f"run {self.__dict__.get('dir')} has no table '{name}' (tables: {', '.join(tables)})")

    def __repr__(self):
        return f"<budjam.Run {self.dir} status={self.summary.get('status')} tables={list(self.tables)}>"


def load_run(directory):
    """Read a finished run directory: a Run with .summary (dict) and one DataFrame per CSV table."""
    return Run(directory)


def grow(scene, seed=None, set=(), callback=None):
    """Grow the scene (a .toml path) with the same driver as `budjam grow`, without writing files.

    seed (0 ≤ seed < 2**63) overrides run.seed; set is a list of "section.key=value" overrides.
    Without callback, returns the Growth iterator of events (see Growth); with one, calls
    callback(event) for every event and returns the final status ('finished', or an expected early
    stop such as 'step_limit')."""
    growth = Growth(str(scene), seed, list(set))
    if callback is None:
        return growth
    for event in growth:
        callback(event)
    return growth.status
