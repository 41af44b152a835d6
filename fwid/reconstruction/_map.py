"""The recording map: a TOML file that says where a lab's own files (CSV, TSV, or MATLAB,
NumPy and HDF5 arrays: `_arrays.py`) keep the time, the pose, the onboard sensors and the
controls, in which units and axes.

```toml
[time]                      # the time base of the file that holds the pose
column = "timeTick"         # a column, unit = "s" | "ms" | "us"
unit = "ms"                 # (or frame_column = "Frame" and rate = 120.0, Hz)

[tracking]                  # the pose (absent: the take is a Motive export)
# file = "{name}_pose.mat"  # the pose's own file beside the recording (default: the recording)
position = ["otX0", "otY0", "otZ0"]
position_unit = "m"         # m | mm
frame = "z-up"              # ned | y-up | z-up, world and body axes alike
attitude = ["otRoll0", "otPitch0", "otYaw0"]   # roll, pitch, yaw; or 4 quaternion, 9 matrix columns
attitude_unit = "deg"       # deg | rad
euler = "ZYX"               # intrinsic order (six); or quaternion = "wxyz" | "xyzw"
# attitude_form = "matrix"  # euler | quaternion | matrix (row-major, body to lab)

[onboard]                   # the autopilot's log
file = "{name}.csv"         # "{name}.onboard.csv" by default; "{name}.csv": the take itself
acc = ["accX", "accY", "accZ"]       # accelerometer (optional), acc_unit = "g" | "m/s2"
gyro = ["gyro.x", "gyro.y", "gyro.z"]  # gyro (optional), gyro_unit = "deg/s" | "rad/s"
axes = "flu"                # the sensors' body axes: frd | flu
time = "t"                  # a log file of its own: its clock's column, time_unit s | ms | us

[inputs]                    # value = scale * (mean of the columns - offset)
de = { column = "m2", offset = 32767, scale = 9.59e-6 }
f  = { column = ["m1", "m4"], offset = 344.2, scale = 3.849e-4 }
```

Every key is checked when the map is read: an unknown section or key, a unit or a frame
fwid does not know, a column list of the wrong length is one line naming the key and what
it takes. Columns are looked up when a recording is read: a missing one names the map and
the recording.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import NamedTuple

from .._errors import InputError
from ._rotations import FRAMES

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANGLE_UNITS = {"deg": 3.141592653589793 / 180.0, "rad": 1.0}
ACC_UNITS = {"g": None, "m/s2": 1.0}  # g: the vehicle's own g (vehicle.json)
RATE_UNITS = {"deg/s": 3.141592653589793 / 180.0, "rad/s": 1.0}
SENSOR_AXES = ("frd", "flu")
EULER_ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")
QUATERNION_ORDERS = ("wxyz", "xyzw")
#: How the attitude columns hold the attitude, by their number: 3, 4 or 9.
ATTITUDE_FORMS = {"euler": 3, "quaternion": 4, "matrix": 9}
#: The suffixes of a take's file (the take itself as `[onboard] file`: "{name}" and one of them).
TAKE_SUFFIXES = (".csv", ".tsv", ".mat", ".npz", ".h5", ".hdf5")
CONTROLS = ("de", "dr", "f")
DEFAULT_LOG = "{name}.onboard.csv"

_KEYS = {
    "time": {"column", "unit", "frame_column", "rate"},
    "tracking": {"file", "position", "position_unit", "frame", "attitude", "attitude_unit",
                 "euler", "quaternion", "attitude_form"},
    "onboard": {"file", "acc", "acc_unit", "gyro", "gyro_unit", "axes", "time", "time_unit"},
    "inputs": set(CONTROLS),
}


class Control(NamedTuple):
    """One section-1 control from a lab's columns: `scale * (mean(columns) - offset)`."""

    columns: tuple[str, ...]
    offset: float
    scale: float


class RecordingMap(NamedTuple):
    """A recording map as read from its TOML file (module docstring); every unit already
    turned into its factor to SI."""

    path: str
    time_column: str | None
    time_scale: float
    frame_column: str | None
    frame_rate: float | None
    position: tuple[str, str, str] | None
    position_scale: float
    frame: str
    attitude: tuple[str, ...] | None
    angle_scale: float
    euler: str | None
    quaternion: str | None
    log_file: str
    log_time: str
    log_time_scale: float
    acc: tuple[str, str, str] | None
    acc_scale: float | None
    gyro: tuple[str, str, str] | None
    gyro_scale: float
    axes: str
    inputs: dict[str, Control]
    #: euler | quaternion | matrix (nine columns, row-major, body to lab)
    attitude_form: str = "euler"
    #: `[tracking] file`: the pose's own file beside the recording ("{name}" the recording's
    #: name); None: the recording itself
    tracking_file: str | None = None

    @property
    def log_is_take(self) -> bool:
        """Whether the autopilot's columns are in the file that holds the pose (`[onboard]
        file` is `[tracking] file`, or, without one, `"{name}"` with a take's suffix, `.gz`
        allowed)."""
        if self.tracking_file is not None:
            return self.log_file == self.tracking_file
        rest = self.log_file.removeprefix("{name}").removesuffix(".gz")
        return self.log_file.startswith("{name}") and rest in TAKE_SUFFIXES

    def tracking_path(self, take) -> Path:
        """The file that holds the pose of the recording at `take` (a path): `[tracking]
        file` beside it, or the recording itself."""
        from ._raw import take_name

        take = Path(take)
        if self.tracking_file is None:
            return take
        return take.with_name(self.tracking_file.format(name=take_name(take)))

    def side_files(self, take) -> set[Path]:
        """The files of the recording at `take` other than itself: its pose's file and its
        autopilot's log (a folder's takes are its files that are no other take's)."""
        take = Path(take)
        files = {self.tracking_path(take)} | (set() if self.log_is_take else {self.log_path(take)})
        return files - {take}

    def named(self, take: bool = True) -> list[tuple[str, str]]:
        """`(key, column)` of every column the map reads from the take (`take`: the pose,
        and the autopilot's columns when they are in the take) or from the autopilot's own
        log, the key as the map writes it (for messages)."""
        out = []
        if take:
            out += [("[tracking] position", c) for c in self.position or ()]
            out += [("[tracking] attitude", c) for c in self.attitude or ()]
        if not take or self.log_is_take:
            out += [(f"[inputs] {k}", c) for k, ctl in self.inputs.items() for c in ctl.columns]
            out += [("[onboard] acc", c) for c in self.acc or ()]
            out += [("[onboard] gyro", c) for c in self.gyro or ()]
        return out

    def time_named(self) -> tuple[str, str]:
        """`(key, column)` of the take's time base."""
        if self.time_column is None and self.frame_column is not None:
            return "[time] frame_column", self.frame_column
        return "[time] column", self.time_column

    def log_path(self, take) -> Path:
        """The autopilot log of the take at `take` (a path)."""
        from ._raw import take_name

        take = Path(take)
        return take.with_name(self.log_file.format(name=take_name(take)))

    def log_columns(self) -> list[str]:
        """Every column the map reads from the autopilot's log."""
        cols = [c for ctl in self.inputs.values() for c in ctl.columns]
        return cols + list(self.acc or ()) + list(self.gyro or ())


def _fail(path, key, what) -> InputError:
    return InputError(f"{path}: {key}: {what}; see the guide's page on recordings "
                      "(docs/guide/recordings.md)")


def _choice(path, sec, d, key, table, default=None):
    v = d.get(key, default)
    if v is None:
        return None
    if not isinstance(v, str) or v not in table:
        raise _fail(path, f"[{sec}] {key}", f"{v!r} is not one of {', '.join(table)}")
    return v


def _columns(path, sec, d, key, sizes):
    v = d.get(key)
    if v is None:
        return None
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not all(isinstance(c, str) and c for c in v) or len(v) not in sizes:
        n = " or ".join(str(s) for s in sizes)
        raise _fail(path, f"[{sec}] {key}", f"{v!r} must be a list of {n} column names")
    return tuple(v)


def _number(path, key, v, positive=False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (positive and v <= 0):
        raise _fail(path, key, f"{v!r} must be a {'positive ' if positive else ''}number")
    return float(v)


def read_map(path) -> RecordingMap:
    """Read and check a recording map: a TOML file naming a lab's columns, units and axes.

    The keys are those of the guide's page on your lab's recordings: `[time]`, `[tracking]`,
    `[onboard]` and `[inputs]`.

    **Arguments:**
    - `path`: the map's TOML file.

    **Returns:** a `fwid.reconstruction.RecordingMap`, every unit turned into its factor to SI
    units. An unknown section, key, unit or frame, or a malformed entry, is a
    [`fwid.InputError`][] naming the map and the key.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"--map {path}: no such file")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"--map {path}: cannot read the map ({e})") from None
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"--map {path}: not valid TOML ({e}); see the guide's page on "
                         "recordings (docs/guide/recordings.md)") from None
    for sec, body in doc.items():
        if sec not in _KEYS:
            raise _fail(path, f"[{sec}]", f"unknown section; a map has {', '.join(_KEYS)}")
        if not isinstance(body, dict):
            raise _fail(path, sec, "must be a section ([" + sec + "])")
        bad = sorted(set(body) - _KEYS[sec])
        if bad:
            raise _fail(path, f"[{sec}] {bad[0]}",
                        f"unknown key; [{sec}] takes {', '.join(sorted(_KEYS[sec]))}")
    tm, tr, ob, inp = (doc.get(s, {}) for s in ("time", "tracking", "onboard", "inputs"))
    time_column = tm.get("column")
    frame_column = tm.get("frame_column")
    rate = None
    if frame_column is not None:
        rate = _number(path, "[time] rate", tm.get("rate"), positive=True)
    elif "rate" in tm:
        raise _fail(path, "[time] rate", "goes with frame_column (frame numbers at a rate)")
    if tr and time_column is None and frame_column is None:
        raise _fail(path, "[time]", "give column (and unit) or frame_column and rate")
    position = _columns(path, "tracking", tr, "position", (3,))
    form = _choice(path, "tracking", tr, "attitude_form", ATTITUDE_FORMS)
    attitude = _columns(path, "tracking", tr, "attitude",
                        (ATTITUDE_FORMS[form],) if form else (3, 4, 9))
    if tr and (position is None or attitude is None):
        raise _fail(path, "[tracking]", "needs position (3 columns) and attitude (3 Euler angles, "
                    "4 quaternion components or 9 matrix elements)")
    if attitude is not None and form is None:
        form = {n: f for f, n in ATTITUDE_FORMS.items()}[len(attitude)]
    euler = quaternion = None
    if form == "euler":
        euler = _choice(path, "tracking", {"euler": str(tr.get("euler", "ZYX")).upper()},
                        "euler", EULER_ORDERS)
    elif form == "quaternion":
        quaternion = _choice(path, "tracking", tr, "quaternion", QUATERNION_ORDERS, "wxyz")
    inputs = {}
    for k, v in inp.items():
        extra = sorted(set(v) - {"column", "offset", "scale"}) if isinstance(v, dict) else []
        if not isinstance(v, dict) or "column" not in v or extra:
            what = f"unknown key {extra[0]!r}; " if extra else ""
            raise _fail(path, f"[inputs] {k}", what + "write { column = \"NAME\" (or a list), "
                        "offset = 0.0, scale = 1.0 }")
        inputs[k] = Control(_columns(path, "inputs", v, "column", range(1, 9)),
                            _number(path, f"[inputs] {k}.offset", v.get("offset", 0.0)),
                            _number(path, f"[inputs] {k}.scale", v.get("scale", 1.0)))
    log_file = ob.get("file", DEFAULT_LOG)
    if not isinstance(log_file, str) or "{name}" not in log_file:
        raise _fail(path, "[onboard] file", f"{log_file!r} must name the log with {{name}}, "
                    "the take's name (\"{name}.onboard.csv\", or \"{name}.csv\": the take itself)")
    tracking_file = tr.get("file")
    if tracking_file is not None and (
            not isinstance(tracking_file, str) or "{name}" not in tracking_file
            or not tracking_file.removesuffix(".gz").endswith(TAKE_SUFFIXES)):
        raise _fail(path, "[tracking] file", f"{tracking_file!r} must name the pose's file with "
                    f"{{name}}, the recording's name, and one of {', '.join(TAKE_SUFFIXES)} "
                    "(\"{name}_pose.mat\"); leave it out when the recording holds the pose")
    return RecordingMap(
        str(path), time_column, TIME_UNITS[_choice(path, "time", tm, "unit", TIME_UNITS, "s")],
        frame_column, rate, position,
        LENGTH_UNITS[_choice(path, "tracking", tr, "position_unit", LENGTH_UNITS, "m")],
        _choice(path, "tracking", tr, "frame", FRAMES, "ned"), attitude,
        ANGLE_UNITS[_choice(path, "tracking", tr, "attitude_unit", ANGLE_UNITS, "rad")],
        euler, quaternion, log_file, ob.get("time", "t"),
        TIME_UNITS[_choice(path, "onboard", ob, "time_unit", TIME_UNITS, "s")],
        _columns(path, "onboard", ob, "acc", (3,)),
        ACC_UNITS[_choice(path, "onboard", ob, "acc_unit", ACC_UNITS, "m/s2")],
        _columns(path, "onboard", ob, "gyro", (3,)),
        RATE_UNITS[_choice(path, "onboard", ob, "gyro_unit", RATE_UNITS, "rad/s")],
        _choice(path, "onboard", ob, "axes", SENSOR_AXES, "frd"), inputs, form or "euler",
        tracking_file)
