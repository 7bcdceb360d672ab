"""budjam: growing budding-cell packings, jamming and rigidity, from Python.

Units throughout: lengths in mother diameters D0 = 1, forces in k*D0 (spring constant k = 1),
stresses, pressures and 2D moduli in k, eigenvalues in k/m (m = mother mass), angles in radians,
time in the units of the growth rates (docs/columns.md lists every file's columns and units).

    import budjam
    p = budjam.read_packing("run/packings/jammed.pack")
    p.x, p.y, p.theta, p.b                 # numpy arrays, one entry per cell
    p.lobes()["radius"]                    # lobe 2i: mother of cell i, 2i+1: its bud
    budjam.rigidity(p)["lobe_cluster"]     # rigid cluster of every lobe
    budjam.rigidity(p)["floppy_modes"]     # the keys of `budjam rigidity --json`, its CSV under "table"
    budjam.moduli("run/packings/target_1.pack")["G"]   # a path works wherever a packing does
    p.to_ase(), p.to_gsd_frame(), p.particles()        # ase.Atoms, gsd frame, pandas DataFrame
    budjam.export(p, "jammed.gsd", "gsd")  # for OVITO / HOOMD-blue
    budjam.survival(["run"])["table"]["S"] # Kaplan-Meier S(a) of the buds free at jamming
    run = budjam.load_run("run")           # pandas DataFrames of budjam's tables of a growth run
    run.steps["phi"]
    for event in budjam.grow("scene.toml", seed=3, set={"growth.P0": 1e-3}):
        print(event["kind"], event["phi"])

The functions are the ones `budjam` (the command line) runs, so their results are the same, under
the same names: the result of moduli(), rigidity(), spectrum() and survival() is the JSON of
`budjam moduli`, `rigidity`, `dos` and `survival`, key for key, with the columns of the command's
CSV table (if it writes one) under "table".
"""
import collections.abc
import functools
import numbers
import os
import pathlib
import re

from . import _budjam
from ._budjam import Growth, InputError, NoResultError, OutputError, Packing, __version__, blas

__all__ = ["Growth", "grow", "InputError", "NoResultError", "OutputError", "Packing", "Run", "__version__", "blas",
           "contacts", "export", "gsd_frame", "load_run", "moduli", "particle_frame", "read_packing", "rigidity",
           "spectrum", "survival"]


# pybind11 refuses an argument of the wrong type with a TypeError of several lines listing the C++
# signature; budjam's messages are one line naming the argument, as the command line's are. The
# signature in pybind11's message says what each parameter takes.
_READABLE = {"float": "a number", "int": "an integer", "str": "text (str)", "bool": "True or False",
             "dict": "a dict", "os.PathLike": "a path (str or os.PathLike)", "object": "anything",
             "budjam._budjam.Packing": "a budjam.Packing"}


def _readable(annotation):
    if annotation.startswith("Optional["):
        return _readable(annotation[len("Optional["):-1]) + " or None"
    if annotation.startswith("List["):
        return "a list of " + _readable(annotation[len("List["):-1]).removeprefix("a ").removeprefix("an ")
    if annotation.startswith("numpy.ndarray"):
        return "an array of numbers"
    return _READABLE.get(annotation, annotation)


def _fits(value, annotation):
    """Whether pybind11 would take `value` for a parameter of this annotation (None: cannot tell)."""
    if annotation.startswith("Optional["):
        return value is None or _fits(value, annotation[len("Optional["):-1])
    if annotation.startswith("List["):
        inner = annotation[len("List["):-1]
        return (isinstance(value, collections.abc.Sequence) and not isinstance(value, (str, bytes))
                and all(_fits(v, inner) is not False for v in value))
    if annotation.startswith("numpy.ndarray"):
        import numpy
        try:
            numpy.asarray(value, dtype=numpy.float64)
        except (TypeError, ValueError):
            return False
        return not isinstance(value, (str, bytes))
    checks = {"float": lambda v: isinstance(v, numbers.Real), "int": lambda v: isinstance(v, numbers.Integral),
              "str": lambda v: isinstance(v, str), "bool": lambda v: isinstance(v, bool),
              "dict": lambda v: isinstance(v, collections.abc.Mapping),
              "os.PathLike": lambda v: isinstance(v, (str, os.PathLike)), "object": lambda v: True,
              "budjam._budjam.Packing": lambda v: isinstance(v, Packing)}
    return checks[annotation](value) if annotation in checks else None


def _parameters(signature):
    """[(name, annotation)] of a pybind11 signature's parameter list "a: T, b: U = d"."""
    parts, depth, current = [], 0, ""
    for ch in signature:
        if ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    parts.append(current)
    return [(name.strip(), annotation.split(" = ")[0].strip(), " = " in annotation)
            for name, _, annotation in (p.partition(":") for p in parts if p.strip())]


def _one_line_type_error(name, error, args, kwargs):
    """pybind11's TypeError for wrong argument types as one line naming the first argument that does not
    fit; any other TypeError as it is."""
    text = str(error)
    if "incompatible function arguments" not in text and "incompatible constructor arguments" not in text:
        return error
    match = re.search(r"^\s*1\. [\w.]*\((.*)\)(?: -> .*)?$", text, re.M)
    if match is None:
        return TypeError(f"{name}: an argument of the wrong type")
    parameters = [p for p in _parameters(match.group(1)) if p[0] != "self"]
    names = [p[0] for p in parameters]
    if unknown := [k for k in kwargs if k not in names]:
        return TypeError(f"{name}: no argument named {unknown[0]} (it takes {', '.join(names)})")
    if len(args) > len(parameters):
        return TypeError(f"{name}: at most {len(parameters)} arguments ({', '.join(names)}), got {len(args)}")
    given = list(zip(parameters, args)) + [(p, kwargs[p[0]]) for p in parameters if p[0] in kwargs]
    if missing := [p[0] for p in parameters[len(args):] if not p[2] and p[0] not in kwargs]:
        return TypeError(f"{name}: missing argument {missing[0]}")
    for (parameter, annotation, _), value in given:
        if _fits(value, annotation) is False:
            return TypeError(f"{name}: {parameter}: must be {_readable(annotation)}, got {type(value).__name__}")
    return TypeError(f"{name}: arguments of the wrong type for ({match.group(1)})")


def _one_line_type_errors(name, function, method=False):
    """`function` raising a one-line TypeError (naming the argument) where pybind11 raises its own;
    `method`: its first argument is self, which the signature in the message leaves out."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except TypeError as error:
            one_line = _one_line_type_error(name, error, args[1:] if method else args, kwargs)
            if one_line is error:
                raise
            raise one_line from None

    return wrapper


read_packing = _one_line_type_errors("read_packing", _budjam.read_packing)
Packing.__init__ = _one_line_type_errors("Packing", Packing.__init__, method=True)
Packing.write = _one_line_type_errors("Packing.write", Packing.write, method=True)


def _accepts_paths(function):
    """`function` (first argument a Packing) also taking the path of a packing file (str or os.PathLike)."""
    checked = _one_line_type_errors(function.__name__, function)

    @functools.wraps(function)
    def wrapper(packing, *args, **kwargs):
        if isinstance(packing, (str, os.PathLike)):
            packing = read_packing(packing)
        elif not isinstance(packing, Packing):
            raise TypeError(f"{function.__name__}: packing: must be a budjam.Packing or the path of a packing file "
                            f"(str or os.PathLike), got {type(packing).__name__}")
        return checked(packing, *args, **kwargs)

    return wrapper


_survival = _one_line_type_errors("survival", _budjam.survival)


@functools.wraps(_budjam.survival)
def survival(runs, epsilon=None):
    # One run directory given by its path is a list of one, as `budjam survival RUNDIR` takes it.
    return _survival([runs] if isinstance(runs, (str, os.PathLike)) else runs, epsilon)


contacts = _accepts_paths(_budjam.contacts)
rigidity = _accepts_paths(_budjam.rigidity)
moduli = _accepts_paths(_budjam.moduli)
spectrum = _accepts_paths(_budjam.spectrum)
particle_frame = _accepts_paths(_budjam.particle_frame)


_export = _accepts_paths(_budjam.export)


@functools.wraps(_budjam.export)
def export(packing, path, format, network="load-bearing"):
    # A packing given by its path is never overwritten by its own export (as on the command line).
    if isinstance(packing, (str, os.PathLike)):
        return _export(read_packing(packing), path, format, network, source=packing)
    return _export(packing, path, format, network)


gsd_frame = _accepts_paths(_budjam.gsd_frame)


def _lobe_columns(frame):
    """Per-lobe columns of a particle_frame: type (mother/bud), x, y (unwrapped, cells whole),
    wrapped_x, wrapped_y, image_x, image_y, radius (D0), cell_id (row of the packing), id (lineage),
    rigid_cluster (-1 for a rattler), rattler: the names of the export formats' columns."""
    import numpy

    n = len(frame["radius"])
    return {"type": numpy.where(numpy.arange(n) % 2 == 1, "bud", "mother"),
            **{k: frame[k] for k in ("x", "y", "wrapped_x", "wrapped_y", "image_x", "image_y", "radius")},
            "cell_id": numpy.arange(n) // 2, **{k: frame[k] for k in ("id", "rigid_cluster", "rattler")}}


def _particles(packing, network="load-bearing"):
    """The particles of `budjam export` as a pandas DataFrame, one row per lobe (lobe 2i: mother of
    cell i, 2i+1: its bud): type, x, y, wrapped_x, wrapped_y, image_x, image_y, radius, cell_id, id,
    rigid_cluster, rattler (docs/files.md, "Export")."""
    import pandas

    return pandas.DataFrame(_lobe_columns(particle_frame(packing, network)))


def _to_ase(packing, network="load-bearing"):
    """The packing as ase.Atoms, as `budjam export --format xyz` writes it and ase.io.read reads it:
    one atom per lobe at its wrapped position (z = 0), cell vectors (L, 0, 0), (shear*L, L, 0),
    (0, 0, 1), pbc (True, True, False); arrays type, radius, cell_id, id, rigid_cluster, rattler; info step."""
    import ase
    import numpy

    frame = particle_frame(packing, network)
    columns = _lobe_columns(frame)
    L, shear = frame["L"], frame["shear"]
    positions = numpy.zeros((len(frame["radius"]), 3))
    positions[:, 0], positions[:, 1] = frame["wrapped_x"], frame["wrapped_y"]
    atoms = ase.Atoms(positions=positions, cell=[[L, 0, 0], [shear * L, L, 0], [0, 0, 1]], pbc=[True, True, False])
    for column in ("type", "radius", "cell_id", "id", "rigid_cluster", "rattler"):
        atoms.new_array(column, numpy.asarray(columns[column]))
    atoms.info["step"] = frame["step"]
    return atoms


Packing.particles = _particles
Packing.to_ase = _to_ase
Packing.to_gsd_frame = gsd_frame


class Run:
    """A finished growth-run directory (`budjam grow`), read by budjam's own reader (the one of
    `budjam analyse`) and checked as it checks it: summary.json as a dict and each table budjam
    writes there as a pandas DataFrame, by name: run.steps, run.divisions, run.bud_events, run.moduli,
    run.dos, run.rigidity_events, run.trials (those the scene asked for; other files in the directory
    are not read). Columns are int64 where every field is an integer, bool where every field is
    true/false, float64 where every field is a number (numbers read back bit-identically; an empty
    field, e.g. a P0 of "no feedback" or a quantity not reached, is NaN), text otherwise. Packing
    files are listed in run.packings. A damaged file raises InputError naming it."""

    def __init__(self, directory):
        import pandas

        self.dir = pathlib.Path(directory)
        self.summary, tables = _budjam.read_run(self.dir)
        self.tables = {name: pandas.DataFrame(columns) for name, columns in tables.items()}
        self.packings = sorted((self.dir / "packings").glob("*.pack"))

    def __getattr__(self, name):
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return tables[name]
        raise AttributeError(f"run {self.__dict__.get('dir')} has no table '{name}' (tables: {', '.join(tables)})")

    def __repr__(self):
        return f"<budjam.Run {self.dir} status={self.summary.get('status')} tables={list(self.tables)}>"


def load_run(directory):
    """Read a finished run directory: a Run with .summary (dict) and one DataFrame per budjam table."""
    if not isinstance(directory, (str, os.PathLike)):
        raise TypeError(f"load_run: directory: must be a path (str or os.PathLike), got {type(directory).__name__}")
    return Run(directory)


def _override_value(value):
    """A Python value as the text of a `--set` value: TOML booleans, numbers that read back equal,
    None as "none" (growth.P0: no feedback), lists as TOML arrays, text as given."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "none"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_override_value(v) for v in value) + "]"
    return repr(value) if isinstance(value, float) else str(value)


def _overrides(set):
    """`set` as the list of "section.key=value" strings that `budjam grow --set` takes."""
    if isinstance(set, str):
        return [set]
    if isinstance(set, collections.abc.Mapping):
        return [f"{key}={_override_value(value)}" for key, value in set.items()]
    items = list(set) if isinstance(set, collections.abc.Iterable) else None
    if items is not None and all(isinstance(item, str) for item in items):
        return items
    got = type(set).__name__ if items is None else \
        f"a {type(set).__name__} holding {next(type(i).__name__ for i in items if not isinstance(i, str))}"
    raise TypeError(f"grow: set: must be a dict of scene keys, a \"section.key=value\" string or a list of them, "
                    f"got {got}")


def _seed(seed):
    """`seed` checked as `budjam grow --seed` checks it: a one-line error, never a conversion's."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed: must be an integer, got {type(seed).__name__}")
    if not 0 <= seed < 2**63:
        raise InputError(f"run.seed: must be ≥ 0 and below 2^63 (got {int(seed)})")
    return int(seed)


def grow(scene, seed=None, set=(), callback=None):
    """Grow the scene (a .toml path) with the same driver as `budjam grow`, without writing files.

    seed (0 ≤ seed < 2**63) overrides run.seed. set overrides scene keys as `--set` does: a dict
    {"growth.P0": 1e-3, "growth.max_steps": 500} (None is "none", lists are arrays), one
    "section.key=value" string, or a list of them.
    Without callback, returns the Growth iterator of events (see Growth); with one, calls
    callback(event) for every event and returns the final status ('finished', 'step_limit', or a
    failure such as 'minimiser_failed' or 'overlap_bound': no exception, so check it)."""
    if not isinstance(scene, (str, os.PathLike)):
        raise TypeError(f"scene: must be the path of a scene file (str or os.PathLike), got {type(scene).__name__}")
    if callback is not None and not callable(callback):
        raise TypeError(f"grow: callback: must be callable (or None), got {type(callback).__name__}")
    growth = Growth(os.fspath(scene), _seed(seed), _overrides(set))
    if callback is None:
        return growth
    for event in growth:
        callback(event)
    return growth.status
