"""The `fwid` command line's arguments (the command line of the guide's 'Formats and
interfaces' page): every option with its help, default and choices."""

from __future__ import annotations

import argparse
from collections.abc import Sequence


class _Effects(Sequence):
    """The effects `fwid simulate --effect` takes, from `fwid.synth` (which imports JAX) only
    when they are needed: for `fwid simulate` and its help, not for `fwid --help`."""

    def _all(self):
        from fwid.synth import ALIASES, EFFECTS, OUT_OF_CATALOGUE

        return EFFECTS + OUT_OF_CATALOGUE + tuple(ALIASES)

    def __getitem__(self, i):
        return self._all()[i]

    def __len__(self):
        return len(self._all())


class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Help that says an option's default where it tells something: not for a flag (on or
    off is in its name), not for `None` (the help says what happens without the option),
    and not twice (a help that already names its default)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if (action.default is None or isinstance(action.default, bool)
                or action.default is argparse.SUPPRESS or "default" in text.lower()):
            return text
        return super()._get_help_string(action)


def _prefix(text: str) -> str:
    """A `--prefix` that makes plain file names (letters, digits, `-`, `_`, `.`)."""
    if not text or text[0] == "." or not all(c.isalnum() or c in "-_." for c in text):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a plain file name prefix; use letters, digits, '-', '_' or '.'")
    return text


def parser() -> argparse.ArgumentParser:
    from fwid import __version__

    fmt = _Formatter
    p = argparse.ArgumentParser(
        prog="fwid",
        description="Identify flapping-wing vehicle dynamics from flight data (Armanini et al.).",
    )
    p.add_argument("--version", action="version", version=f"fwid {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("simulate", help="write simulated DelFly-like flights (the default data)",
                       formatter_class=fmt)
    s.add_argument("out_dir", help="folder to write the flight CSVs and vehicle.json into")
    s.add_argument("--flights", type=int, default=4, help="number of flights")
    s.add_argument("--axis", choices=("lon", "lat"), default="lon",
                   help="manoeuvre axis: elevator (lon) or rudder (lat)")
    s.add_argument("--effect", choices=_Effects(), default="none", metavar="EFFECT",
                   help="unmodelled effect to inject, one of: %(choices)s (sensor-offset is the "
                        "old name of time-offset)")
    s.add_argument("--form", default=None,
                   help="the effect's form (fwid.synth.FORMS: e.g. lag, delay, servo, rate-limit "
                        "for actuator-dynamics; an unknown form lists the effect's forms); "
                        "default: its first")
    s.add_argument("--strength", type=float, default=1.0,
                   help="effect strength (1: as strong as the noise on its loads)")
    s.add_argument("--seed", type=int, default=0, help="random seed")
    s.add_argument("--prefix", type=_prefix, default=None,
                   help="file names PREFIX_0.csv, PREFIX_1.csv, ... (default: the axis, "
                   "lon_0.csv, ...), so that sets written by separate calls never collide")
    s.add_argument("--duration", type=float, default=4.5, help="seconds per flight")
    s.add_argument("--drift", action="store_true", help="drifting flapping frequency")
    r = s.add_argument_group("raw recordings (the guide's 'Formats and interfaces' page, "
                             "docs/reference/formats.md; the 6-DOF nonlinear flight)")
    r.add_argument("--raw", nargs="?", const="fwid",
                   choices=("fwid", "motive", "vicon", "qtm", "qtm-mat", "matlab"), default=None,
                   help="write raw recordings instead of flights: the fwid raw CSV (NED); a "
                        "Motive CSV export (y-up mm, a second rigid body), a Vicon Nexus CSV "
                        "export (z-up), a QTM 6DOF TSV (qtm) or MATLAB (qtm-mat) export, each "
                        "with the autopilot log NAME.onboard.csv; or a lab's MATLAB log (matlab) "
                        "with its map lab.toml; the truth goes to OUT_DIR/truth/")
    r.add_argument("--rate", type=float, default=None, help="tracking frame rate [Hz] (200)")
    r.add_argument("--position-noise", type=float, default=None,
                   help="tracking position noise, 1 sigma per axis [mm] (0.4)")
    r.add_argument("--attitude-noise", type=float, default=None,
                   help="tracking attitude noise, 1 sigma per axis [deg] (0.15)")
    r.add_argument("--dropouts", type=float, default=None,
                   help="share of frames where tracking lost the body (0.005)")
    r.add_argument("--onboard-rate", type=float, default=None,
                   help="autopilot log rate [Hz] (512; the forms with a log)")
    r.add_argument("--clock-offset", type=float, default=None,
                   help="t_tracking - t_onboard [s] (random in +-200 s; the forms with a log)")

    tp = sub.add_parser("template", help="write an example flight folder to overwrite with "
                        "your own data (columns, units, vehicle.json explained in README.txt)",
                        formatter_class=fmt)
    tp.add_argument("out_dir", help="new folder to write the example into")
    tp.add_argument("--axis", choices=("lon", "lat"), default="lon",
                    help="longitudinal or lateral example")

    i = sub.add_parser("identify", help="identify a model from flights", formatter_class=fmt)
    i.add_argument("data", nargs="+", help="CSV files or folders of them")
    i.add_argument("--model", choices=("lon", "lat", "flap", "combined"), required=True,
                   help="cycle-averaged longitudinal/lateral (Sec. IV), flapping Fourier "
                   "model (Sec. V) or both combined (Sec. VI)")
    i.add_argument("--joint", action="store_true",
                   help="one parameter set for all flights (each keeps its own biases); with "
                   "--validate, each flight is also fitted alone and the report says which "
                   "validates better on the held-out flights (joint_vs_individual)")
    i.add_argument("--validate", nargs="+", default=[], metavar="DATA",
                   help="held-out flights (CSV files or folders) to validate on")
    i.add_argument("--out", default=None,
                   help="folder for report.json and the figures (without it nothing is written)")
    i.add_argument("--cutoff", type=float, default=5.0, help="cycle-averaged / flapping split [Hz]")
    i.add_argument("--figures", choices=("summary", "all", "none"), default="summary",
                   help="lon/lat: one overview of all flights' fits (the worst and best few "
                   "when many) and the poles (summary), plus one figure per flight (all), or "
                   "none; flap/combined: their figures (summary, all) or none")
    i.add_argument("--method", choices=("output-error", "equation-error", "multiple-shooting",
                                        "filter-error"),
                   default="output-error",
                   help="lon/lat: the estimator: output error (the paper's), equation error "
                   "(least squares of the reconstructed loads on the states: no simulation, "
                   "where an unstable vehicle flown in closed loop is begun), multiple "
                   "shooting (an unstable vehicle: the simulation restarts from the measured "
                   "states every few samples) or filter error (process noise, closed-loop "
                   "flights: a Kalman filter in the likelihood; both start from equation "
                   "error)")
    i.add_argument("--noise", choices=("auto", "full", "diagonal"), default=None,
                   help="lon/lat: the measurement-noise covariance R: full, diagonal "
                   "(uncorrelated output noise), or auto (default: full, replaced by "
                   "diagonal where the full one fails)")
    i.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="lon/lat: hold parameter NAME at VALUE instead of estimating it "
                   "(repeat for several), e.g. --fix Xw=0")
    i.add_argument("--prior", default=None, metavar="PRIOR.json",
                   help="lon/lat: a Gaussian prior on parameters, {\"Mq\": {\"mean\": .., "
                   "\"std\": ..}, ..}, or an earlier report.json (its parameters and std): "
                   "the fit is the maximum a posteriori estimate")
    i.add_argument("--bounds", default=None, metavar="BOUNDS.json",
                   help="lon/lat: parameter bounds, {\"Mq\": {\"low\": .., \"high\": ..}, ..} "
                   "(null or a missing key: open), kept by a bounded Gauss-Newton step")
    i.add_argument("--quiet", action="store_true", help="no progress lines")
    i.add_argument("--window", default=None, metavar="START:END",
                   help="keep each flight's rows with START <= t <= END (seconds on its own t "
                   "column, not from 0; START: or :END open), every flight given; the trim "
                   "is estimated from the start of what is kept")

    rc = sub.add_parser("reconstruct", help="raw tracking takes and autopilot logs to flights: "
                        "smoothed states and loads (the guide's 'Formats and interfaces' page, "
                        "docs/reference/formats.md)", formatter_class=fmt)
    rc.add_argument("raw", nargs="+", metavar="RAW",
                    help="raw takes: fwid raw CSVs, Motive or Vicon Nexus CSV exports, QTM "
                    "6DOF TSV or MATLAB exports, or a lab's own logs read through --map; or "
                    "folders of them (their top-level *.csv, *.tsv, *.mat, gzipped or not, not "
                    "*.onboard.csv)")
    rc.add_argument("--out", required=True, help="folder for the flights, vehicle.json, "
                    "reconstruction.json and one figure per take")
    rc.add_argument("--body", default=None, help="the rigid body's (Vicon segment's) name "
                    "(needed when the take holds several)")
    rc.add_argument("--frame", choices=("ned", "y-up", "z-up"), default=None,
                    help="the recording's world frame, body axes alike (default: ned for the "
                    "fwid raw CSV, y-up for Motive, z-up for Vicon and QTM)")
    rc.add_argument("--onboard", default=None, metavar="LOG.csv",
                    help="the autopilot log of a single tracking take (default: NAME.onboard.csv "
                    "beside it)")
    rc.add_argument("--clock-offset", type=float, default=None, metavar="S",
                    help="t_tracking = t_onboard + S, instead of finding it from the gyro")
    rc.add_argument("--max-dropout", type=float, default=0.1, metavar="S",
                    help="longest tracking gap bridged (s); the take is split at longer ones "
                    "and each airborne stretch of 5 s made a flight (NAME.csv the longest, "
                    "NAME_2.csv ... the others)")
    rc.add_argument("--keep-ground", action="store_true",
                    help="keep the whole record: no cut to where the vehicle is airborne "
                    "(the rests on the ground are still named in reconstruction.json)")
    rc.add_argument("--min-overlap", type=float, default=2.0, metavar="S",
                    help="shortest overlap of take and autopilot log accepted (s)")
    rc.add_argument("--map", default=None, metavar="MAP.toml", dest="recording_map",
                    help="a recording map: where a lab's own CSV files keep the time, the pose, "
                    "the onboard sensors and the controls, in which units and axes")
    rc.add_argument("--strict-frame", action="store_true",
                    help="refuse a take whose onboard sensors contradict the map's frame or "
                    "angle signs, instead of using the convention they agree with")
    rc.add_argument("--no-figures", dest="figures", action="store_false",
                    help="skip the figure per take")
    rc.add_argument("--quiet", action="store_true", help="no progress lines")

    d = sub.add_parser("diagnose", help="where the model misses, which effect explains it, "
                                        "how far the held-out error shrinks once it is added",
                       formatter_class=fmt)
    d.add_argument("--train", nargs="+", required=True, metavar="DATA",
                   help="flights the models are fitted to (CSV files or folders)")
    d.add_argument("--test", nargs="+", required=True, metavar="DATA",
                   help="held-out flights the shrink is measured on")
    d.add_argument("--axis", choices=("lon", "lat"), default="lon", help="axis to diagnose")
    d.add_argument("--no-simulation", action="store_true",
                   help="skip the gap in the simulated states (the verdict's effects in the EOM, "
                        "re-fitted by output error: the slowest step)")
    d.add_argument("--no-process-noise", action="store_true",
                   help="with a random-disturbance verdict, skip the baseline's filter-error "
                        "fit (the process noise F it takes and its innovations' whiteness)")
    d.add_argument("--out", default=None,
                   help="folder for diagnosis.json and the figure (without it nothing is written)")
    d.add_argument("--no-next-flight", action="store_true",
                   help="with --out and an ambiguous confidence set: skip designing the flight "
                        "that tells the two leading effects apart (next_flight.csv; both "
                        "models re-fitted, then an optimisation: slow)")
    d.add_argument("--quiet", action="store_true", help="no progress lines")
    d.add_argument("--window", default=None, metavar="START:END",
                   help="keep each flight's rows with START <= t <= END (seconds on its own t "
                   "column, not from 0; START: or :END open), every flight given; the trim "
                   "is estimated from the start of what is kept")

    g = sub.add_parser("design", help="design the control input of the next flight through "
                                      "the identified model (smallest parameter variances, "
                                      "or D-optimal)", formatter_class=fmt)
    g.add_argument("--model", choices=("lon", "lat"), default=None,
                   help="the model of the report: elevator (lon) or rudder (lat) input")
    g.add_argument("--from", dest="source", default=None, metavar="REPORT.json",
                   help="report.json of `fwid identify --model lon|lat`")
    g.add_argument("--duration", type=float, default=5.0, help="input length [s]")
    g.add_argument("--amplitude", type=float, default=None,
                   help="peak deflection [rad], perturbation from trim (required, except with "
                        "--discriminate, where without it the next flight `fwid diagnose --out` "
                        "designed is designed again with its recorded settings)")
    g.add_argument("--quiet", type=float, default=1.0,
                   help="zero input for the first QUIET seconds (the trim estimate)")
    g.add_argument("--out", required=True, help="folder for input.csv, design.json, design.png")
    g.add_argument("--parametrisation", choices=("steps", "multisine"), default="steps",
                   help="free piecewise-constant sequence or multisine (free amplitudes and "
                        "phases)")
    g.add_argument("--switch-rate", type=float, default=10.0,
                   help="steps: switching rate [Hz]")
    g.add_argument("--rate", type=float, default=100.0, help="input sample rate [Hz]")
    g.add_argument("--attitude-limit", type=float, default=None,
                   help="bound on the predicted attitude excursion [rad] (80%% of it used); "
                        "default: the excursion of a 3211 of the same amplitude and length")
    g.add_argument("--criterion", choices=("variances", "d-optimal"), default="variances",
                   help="minimise the geometric mean of the parameters' predicted variances "
                        "(default) or maximise log det of their information (D-optimal)")
    g.add_argument("--restarts", type=int, default=16, help="random restarts")
    g.add_argument("--seed", type=int, default=0, help="random seed of the restarts")
    g.add_argument("--no-progress", dest="quiet_progress", action="store_true",
                   help="no progress lines")
    g.add_argument("--discriminate", default=None, metavar="DIAGNOSIS_DIR",
                   help="instead: the input telling apart the two closest effects of the "
                        "diagnosis in DIAGNOSIS_DIR (diagnosis.json), both models re-fitted on "
                        "its training flights")
    g.add_argument("--discriminate-by", choices=("loads", "outputs"), default="loads",
                   help="with --discriminate: compare the two models' predicted loads along "
                        "either model's trajectory (default; what the diagnosis compares) or "
                        "their predicted outputs")
    g.add_argument("--train", nargs="+", default=None, metavar="DATA",
                   help="with --discriminate: the diagnosis's training flights (default: the "
                        "paths its diagnosis.json records)")
    return p
