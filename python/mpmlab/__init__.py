"""mpmlab from Python: configurations, runs stepped under your control, studies, the schema.

    import mpmlab
    cfg = mpmlab.Config.from_file("examples/plate_mms_2d.toml")
    cfg.set("grid.cells", 32)
    run = mpmlab.Run(cfg)                 # set up; nothing is stepped yet
    run.advance(0.5 * run.end_time)       # steps until t >= 0.5 T
    p = run.particles()                   # NumPy copies: x, v, stress, F, id, internal, ...
    summary = run.run()                   # to time.end; summary.json as a dict

The configuration is checked as `mpm run` checks it (an invalid key or value raises
mpmlab.InputError with the command line's message); a run given ``out=`` writes the files
`mpm run --out` writes, byte for byte. Errors are the classes of mpmlab.errors, one per exit code
of `mpm`. Stepping releases the GIL and uses OpenMP threads as `mpm run` does.
"""

import math as _math
import os as _os



def _prefer_passive_waiting():
    """OMP_WAIT_POLICY=passive unless set, as `mpm` does (app/main.cpp: spinning idle threads
    slow a run on a busy machine many times over). libgomp reads it when it is loaded, which
    the native module below does; if it is loaded already, its policy stands and nothing is
    set (summary.json records the variable)."""
    if "OMP_WAIT_POLICY" in _os.environ:
        return
    try:
        with open("/proc/self/maps") as maps:
            if "libgomp" in maps.read():
                return
    except OSError:
        return
    _os.environ["OMP_WAIT_POLICY"] = "passive"


_prefer_passive_waiting()

from . import errors  # noqa: E402
from .errors import *  # noqa: F401,F403,E402
from ._mpmlab import __version__, keys, methods  # noqa: E402
from ._mpmlab import (_Config, _massmatrix, _reconstruct, _reconstruct_2d,  # noqa: E402
                      _restart_config, _Run, _spline_matrix, _study)

__all__ = ["Config", "Run", "study", "reconstruct", "spline_values", "spline_mass",
           "massmatrix", "keys", "methods", "errors", "__version__"] + errors.__all__


def _toml_string(s):
    out = ['"']
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append("\\u%04x" % ord(ch))
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_value(value):
    """The TOML text of a Python value (what `mpm run --set key=TEXT` takes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if _math.isnan(value):
            return "nan"
        if _math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # the shortest text that reads back to the same double
    if isinstance(value, str):
        return _toml_string(value)
    if hasattr(value, "tolist"):  # NumPy arrays and scalars
        return _toml_value(value.tolist())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise InputError(f"{value!r} ({type(value).__name__}) is no configuration value: give a "
                     "number, a boolean, a string or a list of them")


def _toml_document(d):
    """A TOML document of nested dicts (tables) of values, and for each of its lines the key
    path it comes from (``['grid', 'cells']``), for messages."""
    lines, paths, tables = [], [], []

    def emit(table, prefix):
        for key, value in table.items():
            if isinstance(value, dict):
                tables.append((prefix + [str(key)], value))
            else:
                lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
                paths.append(prefix + [str(key)])

    emit(d, [])
    while tables:
        path, table = tables.pop(0)
        lines.append("")
        paths.append(path)
        lines.append("[" + ".".join(_toml_key(k) for k in path) + "]")
        paths.append(path)
        emit(table, path)
    return "\n".join(lines) + "\n", paths


def _toml_key(key):
    key = str(key)
    bare = key and all(c.isalnum() or c in "_-" for c in key) and key.isascii()
    return key if bare else _toml_string(key)


class _Located:
    """Turns ``SOURCE:LINE:COLUMN`` of a TOML text made from a dict into the entry it came from
    (``dict['grid']['cells']``) in the messages of the InputErrors raised inside it."""

    def __init__(self, source=None, paths=()):
        self.source, self.paths = source, paths

    def text(self, message):
        import re

        if not self.paths:  # (not from a dict: the messages name file lines or calls)
            return message

        def entry(m):
            line = int(m.group(1))
            if 1 <= line <= len(self.paths):
                return self.source + "".join(f"[{k!r}]" for k in self.paths[line - 1])
            return m.group(0)

        return re.sub(re.escape(self.source) + r":(\d+):\d+", entry, message)

    def __enter__(self):
        return self

    def __exit__(self, kind, error, traceback):
        if isinstance(error, Error) and kind is not None:
            raise kind(self.text(str(error))) from None
        return False


class Config:
    """A run's configuration, checked against the schema (mpmlab.keys()) as `mpm run` checks it.

    Made by :meth:`from_file`, :meth:`from_dict` or :meth:`from_string`; changed with
    :meth:`set` (or ``cfg[key] = value``), which takes what ``mpm run --set`` takes and refuses
    what it refuses, with its message (mpmlab.InputError), leaving the configuration unchanged.
    """

    def __init__(self, native):
        if not isinstance(native, _Config):
            raise TypeError("make a Config with Config.from_file, from_dict or from_string")
        self._native = native
        self._located = _Located()

    @classmethod
    def from_file(cls, path, overrides=()):
        """Reads a TOML file; ``overrides`` are ``"key=value"`` texts as ``--set`` takes."""
        return cls(_Config.load(_os.fspath(path), list(overrides)))

    @classmethod
    def from_string(cls, text, source="string", overrides=()):
        """Parses TOML text; messages name ``source`` with the line and column."""
        return cls(_Config.parse(text, source, list(overrides)))

    @classmethod
    def from_dict(cls, d, source="dict"):
        """Nested dicts as TOML tables: ``{"grid": {"cells": 16}, "benchmark": "mms_1d"}``.
        Messages (here and of the runs made from it) name the entry, ``dict['grid']['cells']``,
        where a file's name its line."""
        if not isinstance(d, dict):
            raise InputError(f"from_dict: a dict of keys and tables, not {type(d).__name__}")
        text, paths = _toml_document(d)
        located = _Located(source, paths)
        with located:
            cfg = cls.from_string(text, source)
        cfg._located = located
        return cfg

    def set(self, key, value):
        """Sets ``key`` (dotted: ``"grid.cells"``) to ``value``; returns the configuration."""
        self._native.set(key, _toml_value(value), f"Config.set({key!r}, {value!r})")
        return self

    def get(self, key):
        """The value of ``key`` in effect (its default when not set)."""
        return self._native.get(key)

    def __getitem__(self, key):
        return self.get(key)

    def __setitem__(self, key, value):
        self.set(key, value)

    def is_set(self, key):
        return self._native.is_set(key)

    def where(self, key):
        """Where ``key`` was given: ``file:line:column``, the dict entry, the set() call, or
        ``default``."""
        return self._located.text(self._native.where(key))

    def copy(self):
        c = Config(self._native.copy())
        c._located = self._located
        return c

    def to_toml(self):
        """Every key with its value in effect, as the run's config.toml holds it."""
        return self._native.to_toml()

    @property
    def source(self):
        return self._native.source

    def __repr__(self):
        return f"<mpmlab.Config from {self.source or 'nothing'}>"


def _config(config):
    if isinstance(config, Config):
        return config
    if isinstance(config, dict):
        return Config.from_dict(config)
    if isinstance(config, (str, _os.PathLike)):
        return Config.from_file(config)
    raise TypeError("config: a mpmlab.Config, a dict or the path of a TOML file")


class Run:
    """One run, stepped under your control.

    ``Run(config, out=None, overwrite=False, threads=None, progress=False)`` sets the run up (the
    input checks of `mpm run`; nothing is stepped) and, with ``out``, writes its initial
    outputs there. ``threads``: None chooses as `mpm run` does (OMP_NUM_THREADS when set, else
    OpenMP's count capped by the problem size), a number runs that many; the results do not
    depend on it.

    :meth:`step`, :meth:`advance` and :meth:`run` take steps with the GIL released; Ctrl-C
    raises KeyboardInterrupt between two steps, leaving the run intact. A numerical failure
    finishes the run (its summary says "failed") and raises its error class
    (mpmlab.errors.RunFailed and subclasses). :meth:`finish` (which :meth:`run` calls) writes
    summary.json; a run finished before time.end says "interrupted", never "ok".

    Every field (:meth:`particles`, :meth:`grid`, :meth:`history`) is a copy: the particles are
    re-ordered by re-sorting, so a view would not stay the same particles; ``id`` names them.
    """

    def __init__(self, config, out=None, overwrite=False, threads=None, progress=False,
                 _restart=""):
        cfg = _config(config)
        self.config = cfg
        self.out = _os.fspath(out) if out is not None else None
        if threads is None:
            # As `mpm run` without --threads: OMP_NUM_THREADS when set, else OpenMP's count
            # capped by the problem size (0).
            threads = -1 if "OMP_NUM_THREADS" in _os.environ else 0
        with cfg._located:
            self._native = _Run(cfg._native, self.out or "", bool(overwrite), int(threads),
                                bool(progress), _restart)
        self._summary = None

    @classmethod
    def restart(cls, checkpoint, config=None, overrides=(), out=None, overwrite=False,
                threads=None, progress=False):
        """Continues from ``checkpoint`` (a checkpoint.bin), as ``mpm run --restart`` does:
        with its stored configuration, which ``config`` (if given) and ``overrides`` may change
        in output.*, parallel.* and time.end only; the outputs go next to the checkpoint unless
        ``out``."""
        checkpoint = _os.fspath(checkpoint)
        given = _config(config)._native if config is not None else None
        cfg = Config(_restart_config(checkpoint, given, list(overrides)))
        if out is None:
            out = _os.path.dirname(checkpoint) or "."
        return cls(cfg, out=out, overwrite=overwrite, threads=threads, progress=progress,
                   _restart=checkpoint)

    # --- where the run is
    @property
    def dim(self):
        return self._native.dim

    @property
    def dt(self):
        return self._native.dt

    @property
    def total_steps(self):
        """The step of time.end."""
        return self._native.steps

    @property
    def end_time(self):
        return self._native.steps * self._native.dt

    @property
    def current_step(self):
        return self._native.step

    @property
    def time(self):
        return self._native.time

    @property
    def running(self):
        """Can take another step: not at time.end, not failed, not finished."""
        return self._native.running

    @property
    def finished(self):
        return self._native.finished

    @property
    def warnings(self):
        return list(self._native.warnings)

    # --- stepping
    def step(self, n=1):
        """Takes ``n`` steps (fewer at time.end)."""
        self._native.advance_to(self._native.step + int(n))
        return self

    def advance(self, to_time):
        """Takes steps until the time reaches ``to_time`` (the first step at or after it; at
        most time.end)."""
        target = _math.ceil(to_time / self._native.dt - 1e-9)
        self._native.advance_to(max(target, self._native.step))
        return self

    def run(self):
        """Takes the run to time.end and finishes it; returns summary.json as a dict."""
        if not self.finished:
            self._native.advance_to(self._native.steps)
        return self.finish() if not self.finished else self.summary

    def finish(self):
        """Error norms and summary.json; returns the summary as a dict. Once."""
        if self.finished:
            return self.summary
        self._summary = self._native.finish()
        return self._summary

    @property
    def summary(self):
        """summary.json as a dict (after finish())."""
        if self._summary is None:
            self._summary = self._native.summary()
        return self._summary

    def checkpoint(self):
        """Writes checkpoint.bin of the state now into the output directory."""
        self._native.checkpoint()

    # --- the state
    def particles(self):
        """The particles' fields as NumPy copies: x, x0, v (n, dim); stress, F (n, dim, dim);
        mass, volume, volume0 (n); id, material (n, integers); internal: the material's internal
        variables by name (n each)."""
        return self._native.particles()

    @property
    def positions(self):
        return self.particles()["x"]

    @property
    def velocities(self):
        return self.particles()["v"]

    @property
    def stress(self):
        return self.particles()["stress"]

    @property
    def F(self):
        return self.particles()["F"]

    @property
    def ids(self):
        return self.particles()["id"]

    def grid(self):
        """The grid's nodal fields of the last step as NumPy copies, one row per degree of
        freedom: x (its position), mass, momentum, velocity, force, acceleration, active (the
        DOFs solved for), fixed (bit d: component d prescribed)."""
        return self._native.grid()

    def history(self):
        """history.csv's columns as NumPy arrays (kept with or without an output directory)."""
        columns, values = self._native.history()
        return {name: values[:, k].copy() for k, name in enumerate(columns)}

    def reactions(self):
        """The reaction force on each constrained boundary in the last step, by history.csv's
        column name (``reaction_prescribed_y``, ...; output.reactions = true): N, or N/m in 2D."""
        return dict(self._native.reactions())

    def set_prescribed_velocity(self, velocity):
        """Sets the velocity [m/s] of the box of prescribed velocities ([prescribed]) from the
        next step on, in its prescribed components."""
        self._native.set_prescribed_velocity([float(v) for v in velocity])

    def __repr__(self):
        return (f"<mpmlab.Run {self.dim}D step {self.current_step}/{self.total_steps} "
                f"t = {self.time:.6g} s{' finished' if self.finished else ''}>")


def study(config, refine, methods=None, out=None, jobs=1, overwrite=False, frame=None):
    """The refinement study of `mpm study`: ``refine`` maps the refined key to its values,
    coarse to fine (``{"grid.cells": [8, 16, 32]}``); further keys are refined in lockstep
    (``"time.dt"`` with the cells). ``methods``: labels as ``mpm study --methods`` takes
    (``"bspline2/tls/consistent"``); none: the configuration's method. With ``out``, study.csv,
    study.txt and every run's files are written there.

    Returns one row per run, method after method: study.csv's columns, ``failure``, and
    ``order_<error>`` for each error against the method's previous value (as study.txt prints
    them). A pandas DataFrame when pandas is installed (``frame=None`` or True), else a list of
    dicts."""
    cfg = _config(config)
    if not isinstance(refine, dict) or not refine:
        raise InputError("refine: a dict of the refined key to its values, "
                         "e.g. {'grid.cells': [8, 16, 32]}")
    texts = [f"{key}=" + ",".join(_refine_value(v) for v in values)
             for key, values in refine.items()]
    if methods is None:
        methods_text = ""
    elif isinstance(methods, str):
        methods_text = methods
    else:
        methods_text = ",".join(methods)
    with cfg._located:
        rows = _study(cfg._native, texts, methods_text, _os.fspath(out) if out else "",
                      int(jobs), bool(overwrite))
    if frame is False:
        return rows
    try:
        import pandas
    except ImportError:
        if frame:
            raise
        return rows
    return pandas.DataFrame(rows)


def _refine_value(v):
    if isinstance(v, float):
        return repr(v)
    return str(v)


def reconstruct(x, f, lower, upper, cells, at, mapping="tls", terms=3, completion="virtual",
                max_condition=1e8, mls_degree=1, element_integrals=None, share_faces=False,
                details=False):
    """The reconstructions of `mpm reconstruct` on arrays: values ``f`` at points ``x``,
    reconstructed on ``cells`` equal elements of [lower, upper] and evaluated at the points
    ``at`` (a point on an interior face in the element above it, the last face in the last).

    1D (``x`` of shape (n,) or (n, 1)): ``mapping`` "tls", "cubic_spline", "mls" or "imls"
    (D 5.2.3, 003). 2D (``x`` and ``at`` of shape (n, 2); ``lower``, ``upper``, ``cells`` one
    value or one per direction): TLS on the rectangles (D 6.2.1), ``terms`` 1, 3 or 6.

    TLS: ``terms`` Taylor terms (1D 1-3), ``completion`` for elements with too few points
    ("reduce", "virtual", "neighbour", "none": raises), ``element_integrals`` (one per element,
    x fastest) kept exactly by the conservative fit (D eq. 5.9; None: the plain fit). MLS/IMLS:
    the polynomial degree ``mls_degree`` (1 or 2), the quadratic-spline weight of support three
    cells. Returns the values at ``at`` (NumPy), with ``details=True`` also the per-element
    report `mpm reconstruct` prints."""
    import numpy

    pts = numpy.asarray(x, dtype=float)
    values_f = [float(v) for v in numpy.ravel(f)]
    integrals = [] if element_integrals is None else [float(v)
                                                      for v in numpy.ravel(element_integrals)]
    if pts.ndim == 2 and pts.shape[1] == 2:
        if mapping != "tls":
            raise InputError(f"mapping {mapping!r} is one-dimensional; 2D reconstructs with tls "
                             "(D 6.2)")
        _, lo, hi, nc = _box(pts, lower, upper, cells)
        values, text = _reconstruct_2d(pts, values_f, lo, hi, nc,
                                       numpy.asarray(at, dtype=float).reshape(-1, 2), int(terms),
                                       completion, float(max_condition), integrals,
                                       bool(share_faces))
    elif pts.ndim == 1 or (pts.ndim == 2 and pts.shape[1] == 1):
        values, text = _reconstruct(
            [float(v) for v in numpy.ravel(pts)], values_f, float(lower), float(upper),
            int(cells), [float(v) for v in numpy.ravel(at)], mapping, int(terms), completion,
            float(max_condition), int(mls_degree), integrals, bool(share_faces))
    else:
        raise InputError("x: points of shape (n,) or (n, 1) in 1D, (n, 2) in 2D")
    return (values, text) if details else values


def _sparse(parts):
    data, indices, indptr, shape = parts
    try:
        import scipy.sparse
    except ImportError:
        return data, indices, indptr, shape
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)


def _box(points, lower, upper, cells):
    import numpy

    pts = numpy.asarray(points, dtype=float)
    if pts.ndim == 1:
        pts = pts[:, None]
    dim = pts.shape[1]

    def per_dim(v, cast):
        v = numpy.ravel(numpy.asarray(v))
        return [cast(v[0])] * dim if v.size == 1 else [cast(e) for e in v]

    return pts, per_dim(lower, float), per_dim(upper, float), per_dim(cells, int)


def spline_values(points, lower, upper, cells, degree):
    """phi_j(x_k) of the B-splines of ``degree`` (1-5, open knot vectors) on ``cells`` cells of
    the box [lower, upper] (per direction, or one value for all), at the points (n, dim): a
    sparse matrix, points by functions (scipy.sparse.csr_matrix when SciPy is installed, else
    its CSR arrays (data, indices, indptr, shape))."""
    pts, lo, hi, nc = _box(points, lower, upper, cells)
    return _sparse(_spline_matrix(pts, [], lo, hi, nc, int(degree), False))


def spline_mass(points, weights, lower, upper, cells, degree):
    """The mass matrix sum_k w_k phi_i(x_k) phi_j(x_k) of the B-splines of ``degree`` on the box
    (as spline_values), from points (n, dim) with weights (particle masses, or quadrature weights
    times density): MPM's consistent mass matrix (D eq. 2.34), sparse as spline_values."""
    import numpy

    pts, lo, hi, nc = _box(points, lower, upper, cells)
    w = [float(v) for v in numpy.ravel(weights)]
    return _sparse(_spline_matrix(pts, w, lo, hi, nc, int(degree), True))


def massmatrix(dim=2, degrees=(1, 2, 3, 4, 5), cells=(8, 16, 32, 64, 128),
               boundary="dirichlet", particles=0, tolerance=1e-8, matrix_free=False):
    """`mpm massmatrix`: the condition numbers, CG iterations and p-multigrid V-cycles of the
    B-spline mass matrices of 004's test problem (Tables 4.2-4.4), one dict per (degree, cells)
    with 004's values beside (``*_published``; None where it has none). ``particles=N``: the MPM
    matrix of N regular particles per cell and direction instead of exact quadrature."""
    return _massmatrix(int(dim), [int(p) for p in degrees], [int(n) for n in cells], boundary,
                       int(particles), float(tolerance), bool(matrix_free))
