"""A SINDy baseline of the gap diagnosis: what a researcher would write with `pysindy`.

Same load baseline as fwid: the loads split by `fwid`'s decomposition (cycle-averaged below the
5 Hz split, the flapping part above, Section III.B), the cycle-averaged states and inputs as
perturbations from trim, each flight's own constant (and, for the flapping part, its own
3-harmonic series, Eq. 12) taken out, and the linear model of Eqs. (2-6) (the axis's states and
control) always in the model, never thresholded.

A generic library of the catalogue's families (the README's verdict table),
each column labelled with its family:

- `nonlinear-aero`: the monomials of degree 2 and 3 of the axis's cycle-averaged states
  (`pysindy.PolynomialLibrary`);
- `actuator-dynamics`: the deflection through a first-order lag and a pure delay, a few values
  each (`ACT_TAUS`);
- `time-offset`: the deflection shifted earlier by a few values (`LEADS`);
- `unsteady-aero` (unless `derivatives=False`): the time derivatives of the axis's states
  (`pysindy.FiniteDifference`), except the states the load is reconstructed from (their
  derivative *is* the load);
- `lon-lat-coupling`: the other axis's states and control;
- `flap-frequency`: the flapping-frequency deviation and its square;
- `flap-coupling` (flapping part): every cycle-averaged state and input times the harmonics
  `sin k phi`, `cos k phi`, k = 1..3.

Sparse regression: `pysindy.STLSQ` on standardised columns, jointly with the unpenalised
linear model (its columns projected out first, Frisch-Waugh-Lovell), one regression per load
and part. Its threshold is chosen from `THRESHOLDS` (infinity: no term) by leave-one-flight-out
error on the training flights. Verdict: the family whose kept terms lower the test flights'
error most (the test error of the refit without that family's columns minus that with all
kept terms, relative to the linear model's test error, averaged over the loads and parts);
`none` when no family lowers it by more than `MIN_GAIN_PCT` (2 %, as fwid's `MIN_GAIN`).
"""

from __future__ import annotations

import time
import warnings
from collections import defaultdict

import numpy as np
import pysindy as ps

from fwid.diagnosis._catalogue import lagged
from fwid.diagnosis._signals import AXIS_INPUT, AXIS_LOADS, AXIS_STATES, other, signals

__all__ = ["diagnose", "THRESHOLDS"]

#: STLSQ thresholds tried (coefficients of unit-variance columns, in units of the residual's
#: standard deviation); `inf`: the linear model alone.
THRESHOLDS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, np.inf)
ACT_TAUS = (0.02, 0.05, 0.1, 0.2)
LEADS = (0.02, 0.05, 0.1)
OWN = {"X": ("u",), "Z": ("w",), "M": ("q",), "Y": ("v",), "L": ("p", "r"), "N": ("p", "r")}
#: A family is named when leaving it out raises the test error by more than this percentage
#: of the linear model's (averaged over the loads and parts; fwid's `MIN_GAIN`).
MIN_GAIN_PCT = 2.0
#: Cycle-averaged signals are decimated to about this rate [Hz] (they lie below 5 Hz).
SLOW_RATE = 50.0


def _columns(s, axis: str, load: str, band: str, derivatives: bool = True):
    """(target, base columns, effect columns, effect labels) of one flight."""
    xs = np.stack([s.slow[x] for x in AXIS_STATES[axis]], axis=1)
    d = s.slow[AXIS_INPUT[axis]]
    if band == "averaged":
        y = s.loads["averaged"][load]
        base = np.column_stack([xs, d])
        poly = ps.PolynomialLibrary(degree=3, include_bias=False)
        feats = poly.fit_transform(xs)
        cols, labels = [feats[:, len(AXIS_STATES[axis]):]], \
            ["nonlinear-aero"] * (feats.shape[1] - len(AXIS_STATES[axis]))
        act = [lagged(d, s.dt, "lag", t) for t in ACT_TAUS] + \
              [lagged(d, s.dt, "delay", t) for t in ACT_TAUS]
        cols.append(np.stack(act, axis=1))
        labels += ["actuator-dynamics"] * len(act)
        cols.append(np.stack([lagged(d, s.dt, "delay", -t) for t in LEADS], axis=1))
        labels += ["time-offset"] * len(LEADS)
        if derivatives:
            others = [x for x in AXIS_STATES[axis] if x not in OWN[load]]
            fd = ps.FiniteDifference()
            cols.append(np.stack([fd(s.slow[x][:, None], t=s.dt)[:, 0] for x in others],
                                 axis=1))
            labels += ["unsteady-aero"] * len(others)
        o = other(axis)
        cols.append(np.stack([s.slow.get(x, np.zeros(s.n)) for x in AXIS_STATES[o]
                              + (AXIS_INPUT[o],)], axis=1))
        labels += ["lon-lat-coupling"] * 4
        df = s.slow["f"] - np.median(s.slow["f"])
        cols.append(np.stack([df, df * df], axis=1))
        labels += ["flap-frequency"] * 2
        e = np.concatenate(cols, axis=1)
        step = max(1, int(round(1.0 / (SLOW_RATE * s.dt))))
        y, base, e = y[::step], base[::step], e[::step]
        local = np.ones((len(y), 1))
    else:
        y = s.loads["flapping"][load]
        base = np.column_stack([s.fast[x] for x in AXIS_STATES[axis] + (AXIS_INPUT[axis],)])
        slow = [s.slow.get(x, np.zeros(s.n)) for x in AXIS_STATES["lon"] + AXIS_STATES["lat"]
                + ("de", "dr")]
        harm = [f(k * s.phase) for k in (1, 2, 3) for f in (np.sin, np.cos)]
        e = np.stack([x * h for x in slow for h in harm], axis=1)
        labels = ["flap-coupling"] * e.shape[1]
        local = np.column_stack([np.ones(s.n)] + harm)
    # the flight's own local terms (trim load, its flapping series) out of everything
    q, _ = np.linalg.qr(local)

    def proj(a):
        return a - q @ (q.T @ a)

    return proj(y), proj(base), proj(e), labels


def _gram(y, b, e) -> np.ndarray:
    """`[b e y]^T [b e y]`: all a least-squares fit on these rows needs."""
    a = np.column_stack([b, e, y])
    return a.T @ a


def _fit(g, nb, threshold, keep=None):
    """Joint fit, from a Gram matrix `g` (`_gram`, summed over flights), of the unpenalised
    base (`nb` columns) and the thresholded effect columns (those in `keep`, all if `None`):
    the base projected out (Frisch-Waugh-Lovell), STLSQ on a square root of the remaining
    Gram matrix, which has the same normal equations as the samples. Returns the weights
    `w` with residual `[b e y] w`."""
    ne = g.shape[0] - nb - 1
    live = np.ones(ne, bool) if keep is None else keep.copy()
    gbb = g[:nb, :nb]
    ibb = np.linalg.pinv(gbb)
    rest = slice(nb, None)
    gr = g[rest, rest] - g[rest, :nb] @ ibb @ g[:nb, rest]  # Gram of [e y] with b out
    xi = np.zeros(ne)
    if np.isfinite(threshold) and np.any(live):
        var = np.maximum(np.diag(gr)[:ne], 0.0)
        live &= var > 1e-14 * max(var.max(), 1e-300)
        idx = np.append(np.flatnonzero(live), ne)
        sub = gr[np.ix_(idx, idx)]
        sc = np.sqrt(np.diag(sub))
        sc[-1] = max(sc[-1], 1e-300)
        w, v = np.linalg.eigh(sub / np.outer(sc, sc))
        root = (v * np.sqrt(np.maximum(w, 0.0))).T  # root^T root = scaled Gram
        opt = ps.STLSQ(threshold=threshold, alpha=1e-3)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            opt.fit(root[:, :-1], root[:, -1:])
        xi[live] = np.ravel(opt.coef_) * sc[-1] / sc[:-1]
    theta = ibb @ (g[:nb, -1] - g[:nb, nb:nb + ne] @ xi)
    return np.concatenate([-theta, -xi, [1.0]])


def _sse(g, w) -> float:
    return float(w @ g @ w)


def diagnose(train, test, axis: str = "lon", derivatives: bool = True) -> dict:
    """The SINDy peer's verdict on `train` / `test` flights (fwid `Flight`s) of `axis`.

    **Returns:** a dict with `verdict` (a catalogue name or `none`), `families` (per family
    with kept terms: `gain_pct`, how much the test error grows when it is left out and the
    rest refitted, in percent of the linear model's test error, averaged over the loads and
    parts; `terms`, its terms kept), `kept` (the families with `gain_pct` above
    `MIN_GAIN_PCT`, best first) and `wall_s`. With `derivatives=False` the library has no
    `unsteady-aero` columns.
    """
    t0 = time.perf_counter()
    st = [signals(f) for f in train]
    ss = [signals(f) for f in test]
    gains = defaultdict(float)
    terms = defaultdict(int)
    nb = len(AXIS_STATES[axis]) + 1
    regressions = 2 * len(AXIS_LOADS[axis])
    for load in AXIS_LOADS[axis]:
        for band in ("averaged", "flapping"):
            tr = [_columns(s, axis, load, band, derivatives) for s in st]
            labels = np.array(tr[0][3])
            gtr = [_gram(*c[:3]) for c in tr]
            gte = sum(_gram(*_columns(s, axis, load, band, derivatives)[:3]) for s in ss)
            gall = sum(gtr)
            scale = float(sum(g[-1, -1] for g in gtr)) or 1.0

            def cv(th):
                return sum(_sse(g, _fit(gall - g, nb, th)) for g in gtr) / scale

            errs = [cv(th) for th in THRESHOLDS]
            best = min(range(len(THRESHOLDS)), key=lambda i: (errs[i], -i))
            th = THRESHOLDS[best]
            w = _fit(gall, nb, th)
            xi = -w[nb:-1]
            before = _sse(gte, _fit(gall, nb, np.inf))
            after = _sse(gte, w)
            for fam in sorted(set(labels.tolist())):
                mask = labels == fam
                if not np.any(xi[mask] != 0):
                    continue
                without = _sse(gte, _fit(gall, nb, th, keep=~mask))
                gains[fam] += 100.0 * (without - after) / max(before, 1e-300) / regressions
                terms[fam] += int(np.count_nonzero(xi[mask]))
    families = {f: {"gain_pct": g, "terms": terms[f]} for f, g in gains.items()}
    kept = sorted((f for f, v in families.items() if v["gain_pct"] > MIN_GAIN_PCT),
                  key=lambda f: -families[f]["gain_pct"])
    return {"verdict": kept[0] if kept else "none", "kept": kept, "families": families,
            "wall_s": time.perf_counter() - t0}
