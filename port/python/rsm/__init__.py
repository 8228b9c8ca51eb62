"""rsm for Python: the localizer of the rsm C library, through ctypes.

The library's sources and a small C shim (port/python/rsm_py.c) are built
into one shared object inside this package by ``pip install .`` at the
repository's root; nothing is downloaded and no Python headers are needed.
numpy is the one dependency. docs/python.md shows how to use it::

    import rsm
    loc = rsm.Localizer({"map_update_m": 0.3}, pose=(0.0, 0.0, 0.0))
    loc.motion(0.1, 0.0, 0.01)
    rep = loc.scan(stamp_us, ranges, start=-math.pi / 2, step=math.pi / 180)
    rep.pose, rep.cov, rep.track, loc.map().occupancy

Config fields are named by their paths in ``rsm_localizer_config_t``
(``"grid.sigma_m"``, ``"tmap.cell_m"``, ``"map_update_m"``): the names the C
library gives a field it refuses. Poses are (x, y, theta) in metres and
radians; the C side works in float, so values read back are floats widened
to Python's double exactly.
"""

import ctypes
import importlib.machinery
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

__all__ = ["Error", "ConfigError", "Report", "Map", "Localizer", "config_fields", "default_config",
           "odometry_step", "version", "METHOD_PAPER", "METHOD_ICP", "METHOD_ODOMETRY", "METHOD_MAP",
           "OK", "ERR_INVAL", "ERR_RANGE", "ERR_DEGENERATE", "ERR_NOSYS", "ERR_ORDER"]

# rsm_method_t (rsm/localizer.h), for the "method" field.
METHOD_PAPER, METHOD_ICP, METHOD_ODOMETRY, METHOD_MAP = 0, 1, 2, 3
# The rsm_status_t codes (rsm/status.h) this module's errors carry most.
OK, ERR_INVAL, ERR_AGAIN, ERR_RANGE, ERR_DEGENERATE, ERR_NOSYS, ERR_ORDER = 0, -1, -3, -5, -8, -9, -11

_FLOAT, _UNSIGNED, _SIGNED, _ENUM = 0, 1, 2, 3


def _load() -> ctypes.CDLL:
    here = Path(__file__).resolve().parent
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = here / ("_native" + suffix)
        if path.is_file():
            return ctypes.CDLL(str(path))
    raise ImportError(f"rsm: the compiled library (_native*.so) is not in {here}; "
                      "install the package with `pip install .` from the repository's root")


_lib = _load()


def _sig(name, restype, *argtypes):
    fn = getattr(_lib, name)
    fn.restype = restype
    fn.argtypes = list(argtypes)
    return fn


_P = ctypes.c_void_p
_D = ctypes.c_double
_F = ctypes.c_float
_Z = ctypes.c_size_t
_DP = ctypes.POINTER(ctypes.c_double)
_FP = ctypes.POINTER(ctypes.c_float)
_sig("rsmpy_size", _Z)
_sig("rsmpy_align", _Z)
_sig("rsmpy_max_beams", _Z)
_sig("rsmpy_reset", None, _P)
_sig("rsmpy_field_name", ctypes.c_char_p, _Z)
_sig("rsmpy_field_kind", ctypes.c_int, _Z)
_sig("rsmpy_config_set", ctypes.c_int, _P, _Z, _D)
_sig("rsmpy_config_get", ctypes.c_int, _P, _Z, _DP)
_sig("rsmpy_init", ctypes.c_int, _P, _D, _D, _D, ctypes.POINTER(ctypes.c_char_p))
_sig("rsmpy_motion", ctypes.c_int, _P, _F, _F, _F)
_sig("rsmpy_ticks", ctypes.c_int, _P, ctypes.c_uint32, ctypes.c_uint32)
_sig("rsmpy_set_pose", ctypes.c_int, _P, _F, _F, _F)
_sig("rsmpy_scan", ctypes.c_int, _P, ctypes.c_uint64, _Z, _FP, _FP, _F, _F)
_sig("rsmpy_report_name", ctypes.c_char_p, _Z)
_sig("rsmpy_report", None, _P, _DP)
_sig("rsmpy_counter_name", ctypes.c_char_p, _Z)
_sig("rsmpy_counter_len", _Z, _Z)
_sig("rsmpy_counters", None, _P, ctypes.POINTER(ctypes.c_uint32))
_sig("rsmpy_pose", None, _P, _DP, _DP)
_sig("rsmpy_track", ctypes.c_int, _P)
_sig("rsmpy_scan_points", _Z, _P, _FP, _Z)
_sig("rsmpy_map_bounds", ctypes.c_int, _P, _DP)
_sig("rsmpy_map_raster", ctypes.c_int, _P, _D, _D, _D, _Z, _Z, _FP)
_sig("rsm_strerror", ctypes.c_char_p, ctypes.c_int)
_sig("rsm_outcome_name", ctypes.c_char_p, ctypes.c_int)
_sig("rsm_track_name", ctypes.c_char_p, ctypes.c_int)
_sig("rsm_odometry_verdict_name", ctypes.c_char_p, ctypes.c_int)
_sig("rsm_version", ctypes.c_char_p)


def _names(fn) -> Tuple[str, ...]:
    out = []
    while True:
        name = fn(len(out))
        if name is None:
            return tuple(out)
        out.append(name.decode())


_FIELDS = _names(_lib.rsmpy_field_name)
_FIELD_INDEX = {name: i for i, name in enumerate(_FIELDS)}
_REPORT = _names(_lib.rsmpy_report_name)
_COUNTERS = _names(_lib.rsmpy_counter_name)
MAX_BEAMS = int(_lib.rsmpy_max_beams())

# The counters that are arrays, named per element by the library.
_COUNTER_ELEMENT = {"outcome": _lib.rsm_outcome_name, "track": _lib.rsm_track_name}


def _counter_names() -> Tuple[str, ...]:
    out = []
    for i, name in enumerate(_COUNTERS):
        n = int(_lib.rsmpy_counter_len(i))
        if n == 1:
            out.append(name)
        else:
            out.extend(f"{name}.{_COUNTER_ELEMENT[name](k).decode()}" for k in range(n))
    return tuple(out)


_COUNTER_NAMES = _counter_names()


class Error(Exception):
    """A call the C library refused: ``code`` is its status (``rsm.ERR_*``)."""

    def __init__(self, code: int, what: str):
        self.code = code
        super().__init__(f"{what}: {_lib.rsm_strerror(code).decode()} ({code})")


class ConfigError(Error, ValueError):
    """A configuration the localizer does not take (code ERR_INVAL); ``field``
    names the field."""

    def __init__(self, field: str, why: str):
        self.code = ERR_INVAL
        self.field = field
        ValueError.__init__(self, f"config field {field!r} {why}")


def version() -> str:
    """The C library's version (rsm_version())."""
    return _lib.rsm_version().decode()


def config_fields() -> Tuple[str, ...]:
    """Every field of the configuration, by its path in rsm_localizer_config_t."""
    return _FIELDS


def default_config() -> Dict[str, Union[int, float]]:
    """rsm_localizer_config_default(), as a dict of every field."""
    return _State().config()


def odometry_step(prev: Sequence[float], cur: Sequence[float]) -> Tuple[float, float, float]:
    """The motion increment (dx, dy, dtheta; robot frame at ``prev``) between two
    odometry poses, in double as rsm-nav takes it from a log's poses (far from
    the origin a float difference would lose centimetres)."""
    dx, dy = cur[0] - prev[0], cur[1] - prev[1]
    c, s = math.cos(prev[2]), math.sin(prev[2])
    dt = cur[2] - prev[2]
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(dt), math.cos(dt)))


class _State:
    """One C object (rsmpy_t): the configuration, the localizer and a scan,
    in memory of the size and alignment the shim gives."""

    def __init__(self):
        size, align = int(_lib.rsmpy_size()), int(_lib.rsmpy_align())
        self._buf = ctypes.create_string_buffer(size + align)
        base = ctypes.addressof(self._buf)
        self.ptr = ctypes.c_void_p((base + align - 1) // align * align)
        _lib.rsmpy_reset(self.ptr)

    def set(self, name: str, value) -> None:
        i = _FIELD_INDEX.get(name)
        if i is None:
            raise ConfigError(name, "does not exist (rsm.config_fields() lists them)")
        kind = _lib.rsmpy_field_kind(i)
        if isinstance(value, (str, bytes)):
            raise ConfigError(name, f"takes a number, not {value!r}")
        if kind != _FLOAT and isinstance(value, float) and not value.is_integer():
            raise ConfigError(name, f"is a whole number, not {value!r}")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ConfigError(name, f"takes a number, not {value!r}") from None
        if _lib.rsmpy_config_set(self.ptr, i, v) != 0:
            raise ConfigError(name, f"cannot hold {value!r}")

    def config(self) -> Dict[str, Union[int, float]]:
        out = {}
        v = ctypes.c_double()
        for i, name in enumerate(_FIELDS):
            _lib.rsmpy_config_get(self.ptr, i, ctypes.byref(v))
            out[name] = v.value if _lib.rsmpy_field_kind(i) == _FLOAT else int(v.value)
        return out


@dataclass(frozen=True)
class Report:
    """What one scan did (rsm_localizer_report_t)."""

    outcome: str          # "accepted", "first", "poor_fit", ... (rsm_outcome_name)
    track: str            # "tracking", "uncertain" or "lost"
    odometry: str         # what the scan made of odometry's step: "trusted", "refuted", ...
    fit_ratio: float
    recovered: bool       # a recovery search placed this scan
    search_work: int
    pose: Tuple[float, float, float]      # the estimate after the scan
    cov: np.ndarray                       # its covariance, 3 x 3
    measured: Tuple[float, float, float]  # the scan match's measurement (if one was made)
    points: int           # usable readings
    keypoints_cur: int
    keypoints_ref: int
    matches: int
    inliers: int
    iterations: int
    residual_m: float
    mahalanobis_d2: float
    crossing: float
    unpinned: float


@dataclass(frozen=True)
class Map:
    """The persistent map sampled on a raster: ``occupancy[j, i]`` in [0, 1] is
    the map's at x = origin[0] + (i + 0.5) cell, y = origin[1] + (j + 0.5) cell
    (row 0 at the bottom, y up); 0 where nothing was seen."""

    occupancy: np.ndarray
    origin: Tuple[float, float]
    cell: float

    @property
    def extent(self) -> Tuple[float, float, float, float]:
        """(x0, x1, y0, y1) of the raster's outer edges: matplotlib's
        ``imshow(m.occupancy, origin="lower", extent=m.extent)`` draws it in metres."""
        h, w = self.occupancy.shape
        return (self.origin[0], self.origin[0] + w * self.cell, self.origin[1], self.origin[1] + h * self.cell)

    def world(self, i, j):
        """The centre of cell (i, j) (column, row), in metres."""
        return (self.origin[0] + (np.asarray(i) + 0.5) * self.cell,
                self.origin[1] + (np.asarray(j) + 0.5) * self.cell)


class Localizer:
    """One localizer (rsm_localizer_t): the default configuration with the fields
    of ``config`` changed, started at ``pose``. A field that does not exist, a
    value its type cannot hold or one the library refuses raises ConfigError
    naming the field."""

    def __init__(self, config: Optional[Mapping[str, Union[int, float]]] = None,
                 pose: Sequence[float] = (0.0, 0.0, 0.0)):
        self._s = _State()
        for name, value in (config or {}).items():
            self._s.set(name, value)
        x, y, theta = (float(v) for v in pose)
        field = ctypes.c_char_p()
        rc = _lib.rsmpy_init(self._s.ptr, x, y, theta, ctypes.byref(field))
        if rc != OK:
            if field.value is not None:
                raise ConfigError(field.value.decode(), "is out of range (rsm_localizer_config_check)")
            raise Error(rc, f"cannot start at {tuple(pose)}")

    @property
    def config(self) -> Dict[str, Union[int, float]]:
        """The configuration in force, every field."""
        return self._s.config()

    def motion(self, dx: float, dy: float, dtheta: float) -> None:
        """Predicts with an odometry increment (robot frame at the step's start;
        rsm_localizer_motion). A non-finite one raises Error (ERR_RANGE) and is
        counted in counters()["bad_motions"]."""
        rc = _lib.rsmpy_motion(self._s.ptr, dx, dy, dtheta)
        if rc != OK:
            raise Error(rc, "motion")

    def ticks(self, left: int, right: int) -> bool:
        """Predicts from raw wheel encoder counters (rsm_localizer_ticks, the
        config's odometry geometry); False for the first call, which only latches."""
        rc = _lib.rsmpy_ticks(self._s.ptr, left, right)
        if rc == ERR_AGAIN:
            return False
        if rc != OK:
            raise Error(rc, "ticks")
        return True

    def scan(self, stamp_us: int, ranges, angles=None, *, start: Optional[float] = None,
             step: Optional[float] = None) -> Report:
        """Processes one scan (rsm_localizer_scan) taken at ``stamp_us``
        (microseconds, not going backwards: an older stamp raises Error
        ERR_ORDER and the scan is ignored). ``ranges`` in metres (NaN, 0 and
        readings at or beyond the range limit are dropped and counted); beam
        angles (robot frame, CCW) either as ``angles`` or as ``start`` +
        k ``step`` (rsm_scan_set_uniform). Returns the report; a rejected scan
        says why in its outcome."""
        if not (isinstance(stamp_us, (int, np.integer)) and 0 <= stamp_us < 2 ** 64):
            raise ValueError(f"stamp_us must be an integer from 0 to 2^64 - 1, not {stamp_us!r}")
        r = np.ascontiguousarray(ranges, dtype=np.float32).reshape(-1)
        if r.size > MAX_BEAMS:
            raise ValueError(f"{r.size} readings: the library holds at most {MAX_BEAMS} (RSM_MAX_BEAMS)")
        if angles is not None:
            if start is not None or step is not None:
                raise ValueError("give angles or start and step, not both")
            a = np.ascontiguousarray(angles, dtype=np.float32).reshape(-1)
            if a.size != r.size:
                raise ValueError(f"{r.size} ranges but {a.size} angles")
            ap = a.ctypes.data_as(_FP)
            start = step = 0.0
        elif start is None or step is None:
            raise ValueError("give the beam angles, or start and step")
        else:
            ap = None
        rc = _lib.rsmpy_scan(self._s.ptr, int(stamp_us), r.size, r.ctypes.data_as(_FP), ap, start, step)
        if rc != OK:
            raise Error(rc, "scan")
        return self.report

    @property
    def report(self) -> Report:
        """The last scan's report."""
        v = (ctypes.c_double * len(_REPORT))()
        _lib.rsmpy_report(self._s.ptr, v)
        d = dict(zip(_REPORT, v))
        return Report(
            outcome=_lib.rsm_outcome_name(int(d["outcome"])).decode(),
            track=_lib.rsm_track_name(int(d["track"])).decode(),
            odometry=_lib.rsm_odometry_verdict_name(int(d["odometry"])).decode(),
            fit_ratio=d["fit_ratio"], recovered=bool(d["recovered"]), search_work=int(d["search_work"]),
            pose=(d["x"], d["y"], d["theta"]),
            cov=np.array([d[f"cov{k}"] for k in range(9)]).reshape(3, 3),
            measured=(d["measured_x"], d["measured_y"], d["measured_theta"]),
            points=int(d["points"]), keypoints_cur=int(d["keypoints_cur"]),
            keypoints_ref=int(d["keypoints_ref"]), matches=int(d["matches"]), inliers=int(d["inliers"]),
            iterations=int(d["iterations"]), residual_m=d["residual_m"],
            mahalanobis_d2=d["mahalanobis_d2"], crossing=d["crossing"], unpinned=d["unpinned"])

    def _pose_cov(self):
        pose, cov = (ctypes.c_double * 3)(), (ctypes.c_double * 9)()
        _lib.rsmpy_pose(self._s.ptr, pose, cov)
        return tuple(pose), np.array(cov).reshape(3, 3)

    @property
    def pose(self) -> Tuple[float, float, float]:
        """The current estimate (after any motion since the last scan)."""
        return self._pose_cov()[0]

    @property
    def covariance(self) -> np.ndarray:
        """Its covariance, 3 x 3 (x, y, theta)."""
        return self._pose_cov()[1]

    @property
    def track(self) -> str:
        """How far the estimate can be trusted: "tracking", "uncertain" or "lost"."""
        return _lib.rsm_track_name(_lib.rsmpy_track(self._s.ptr)).decode()

    def set_pose(self, x: float, y: float, theta: float) -> None:
        """Puts the estimate at (x, y, theta), covariance zero (rsm_localizer_set_pose)."""
        rc = _lib.rsmpy_set_pose(self._s.ptr, x, y, theta)
        if rc != OK:
            raise Error(rc, "set_pose")

    def counters(self) -> Dict[str, int]:
        """The localizer's counters (rsm_localizer_counters_t), flat: "scans",
        "drops.nan", "outcome.accepted", "track.lost", ..."""
        v = (ctypes.c_uint32 * len(_COUNTER_NAMES))()
        _lib.rsmpy_counters(self._s.ptr, v)
        return dict(zip(_COUNTER_NAMES, (int(x) for x in v)))

    def scan_points(self) -> np.ndarray:
        """The last scan's usable readings in the robot frame, n x 2 (x, y)."""
        out = np.zeros((MAX_BEAMS, 2), dtype=np.float32)
        n = _lib.rsmpy_scan_points(self._s.ptr, out.ctypes.data_as(_FP), MAX_BEAMS)
        return out[:n].copy()

    def map_bounds(self) -> Tuple[float, float, float, float]:
        """The world box (x0, y0, x1, y1) of the persistent map's finest tiles;
        Error ERR_DEGENERATE while the map is empty, ERR_NOSYS for another method."""
        box = (ctypes.c_double * 4)()
        rc = _lib.rsmpy_map_bounds(self._s.ptr, box)
        if rc != OK:
            raise Error(rc, "map")
        return tuple(box)

    def map(self, cell: Optional[float] = None) -> Map:
        """The persistent map over its bounds, sampled every ``cell`` metres
        (default: the finest cell, tmap.cell_m)."""
        x0, y0, x1, y1 = self.map_bounds()
        cell = float(cell if cell is not None else self._s.config()["tmap.cell_m"])
        if not cell > 0.0:
            raise ValueError(f"cell must be positive, not {cell!r}")
        w, h = max(1, round((x1 - x0) / cell)), max(1, round((y1 - y0) / cell))
        occ = np.zeros((h, w), dtype=np.float32)
        rc = _lib.rsmpy_map_raster(self._s.ptr, x0, y0, cell, w, h, occ.ctypes.data_as(_FP))
        if rc != OK:
            raise Error(rc, "map")
        return Map(occupancy=occ, origin=(x0, y0), cell=cell)
