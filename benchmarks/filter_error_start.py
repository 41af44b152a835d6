"""Filter error on unstable and closed-loop flights: how often it converges, before and after
it starts from equation error (with the bounded gain of the discrete corrector).

    python benchmarks/filter_error_start.py [--seeds 12] [--before 7ae4ff9]

Flights of fwid's longitudinal model (Eq. 7), simulated here in numpy (exact discretisation,
the input held over each sample): a Flapper-like vehicle whose short oscillation is
unstable (the real level flight's equation-error estimate, rounded: eigenvalues about
+0.85 +- 3.5j 1/s), and the DelFly of the paper's Table 1 (stable). Each is flown 20 s at
100 Hz in closed loop (an LQR pitch controller on q and theta, a 3211 on the reference),
through turbulence (white load disturbances on X, Z, M: process noise) with measurement noise
on the states and the reconstructed loads. Each flight is fitted by `fwid.fit(...,
method="filter-error")` with its defaults, by the code of this checkout ("after") and, in a
subprocess, by that of the commit `--before` ("before", `git archive` of its `fwid/`). A fit
counts when it converged; the oscillatory mode's error against the truth is reported for
the converged fits. Writes `results/filter_error_start.md`.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import _provenance  # noqa: F401  (this checkout's fwid first)
import numpy as np
from _provenance import markdown, provenance

ROOT = Path(__file__).resolve().parents[1]

#: The Flapper-like unstable vehicle: the level flight's equation-error estimate, rounded.
FLAPPER = dict(Xq=-0.008, Xu=-0.27, Xw=0.006, Xde=6.0, Zq=-0.005, Zu=-0.009, Zw=-0.08,
               Zde=0.6, Mq=-7.3e-4, Mu=3.9e-3, Mw=-1.0e-3, Mde=0.147)
FLAPPER_C = dict(mass=0.103, Iy=4.9e-4, g=9.81, u0=0.0, w0=0.0, theta0=0.0)
DELFLY_C = dict(mass=0.0205, Iy=6e-5, g=9.81, u0=0.3, w0=0.6, theta0=1.2)
DT, SECONDS = 0.01, 20.0


def _case(name):
    import fwid

    if name == "flapper-unstable":
        return fwid.longitudinal(FLAPPER), FLAPPER_C, dict(q=0.02, u=0.01, w=0.01, th=0.004,
                                                           de=0.004)
    return fwid.longitudinal(), DELFLY_C, dict(q=0.02, u=0.005, w=0.005, th=0.004, de=0.01)


def flight(name: str, seed: int) -> dict:
    """One closed-loop flight through turbulence: `t`, `u` (de), `z` (q u w theta), `forces`
    (X Z M), the constants and the true eigenvalues."""
    import scipy.linalg

    import fwid

    model, consts, amp = _case(name)
    ss = fwid.state_space(model, consts)
    A, B = np.asarray(ss.A), np.asarray(ss.B)[:, :1]
    rng = np.random.default_rng(seed)
    n = int(SECONDS / DT) + 1
    t = DT * np.arange(n)
    # LQR pitch controller: holds the attitude of the unstable vehicle
    Q = np.diag([1.0, 0.0, 0.0, 10.0])
    P = scipy.linalg.solve_continuous_are(A, B, Q, np.array([[50.0]]))
    K = (B.T @ P) / 50.0
    Phi = scipy.linalg.expm(A * DT)
    Gam = np.linalg.solve(A, Phi - np.eye(4)) @ B if abs(np.linalg.det(A)) > 1e-12 else B * DT
    ref = np.zeros(n)
    for k, s in enumerate((1, -1, 1, -1)):  # a 3211 on the attitude reference
        edges = (0, 3, 5, 6, 7)
        ref[(t >= 2 + edges[k] * 0.6) & (t < 2 + edges[k + 1] * 0.6)] = s * 0.05
    m, Iy = consts["mass"], consts["Iy"]
    scale = np.array([1.0 / Iy, 1.0 / m, 1.0 / m])  # loads -> state rates (q, u, w)
    gust = rng.normal(size=(n, 3)) * np.array([amp["q"] * Iy, amp["u"] * m, amp["w"] * m]) \
        / np.sqrt(DT) * 0.05
    x = np.zeros(4)
    xs, de = np.zeros((n, 4)), np.zeros(n)
    for k in range(n):
        xs[k] = x
        de[k] = float(-(K @ (x - np.array([0, 0, 0, ref[k]])))[0]) \
            + rng.normal() * amp["de"]
        w = np.zeros(4)
        w[:3] = gust[k] * scale * DT
        x = Phi @ x + (Gam * de[k]).ravel() + w
    p = model.params
    F = np.stack([
        p["Xq"] * xs[:, 0] + p["Xu"] * xs[:, 1] + p["Xw"] * xs[:, 2] + p["Xde"] * de,
        p["Zq"] * xs[:, 0] + p["Zu"] * xs[:, 1] + p["Zw"] * xs[:, 2] + p["Zde"] * de,
        p["Mq"] * xs[:, 0] + p["Mu"] * xs[:, 1] + p["Mw"] * xs[:, 2] + p["Mde"] * de], 1)
    F = np.asarray(F, float) + gust[:, [1, 2, 0]]
    z = xs + rng.normal(size=xs.shape) * np.array([amp["q"], amp["u"], amp["w"], amp["th"]]) * 0.2
    F = F + rng.normal(size=F.shape) * F.std(axis=0) * 0.05
    eig = np.linalg.eigvals(A)
    return dict(t=t, u=de[:, None], z=z, forces=F, consts=consts, name=name,
                eig=[[float(e.real), float(e.imag)] for e in eig])


def fit_all(flights: list[dict]) -> list[dict]:
    """`fwid.fit(method="filter-error")` with its defaults on each flight: converged, the
    oscillatory mode's natural frequency, the fit's warnings."""
    import warnings

    import fwid

    out = []
    for f in flights:
        model, _, _ = _case(f["name"])
        exp = fwid.Experiment(f["t"], f["u"], f["z"], x0=f["z"][0], consts=f["consts"],
                              forces=f["forces"])
        row = {"name": f["name"]}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = fwid.fit(model.with_params({k: 0.0 for k in model.local}), exp,
                             method="filter-error")
            eig = np.asarray(fwid.eigenvalues(r.model, f["consts"]))
            osc = eig[np.abs(eig.imag) > 1e-9]
            row.update(converged=bool(r.converged),
                       wn=float(np.abs(osc[0])) if len(osc) else None,
                       re=float(osc[0].real) if len(osc) else None)
        except Exception as e:  # a fit that raises counts as not converged
            row.update(converged=False, error=f"{type(e).__name__}: {str(e)[:160]}")
        out.append(row)
    return out


def _before(ref: str, flights: list[dict]) -> list[dict]:
    """The fits by the code of commit `ref`, in a subprocess (its `fwid/` on PYTHONPATH)."""
    with tempfile.TemporaryDirectory() as tmp:
        tar = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "fwid"],
                             capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=tar, check=True)
        data = Path(tmp) / "flights.json"
        data.write_text(json.dumps([{k: (v.tolist() if isinstance(v, np.ndarray) else v)
                                     for k, v in f.items()} for f in flights]))
        env = {**__import__("os").environ, "PYTHONPATH": tmp}
        code = ("import json, sys; sys.path.insert(0, %r); import fwid; "
                "sys.path.insert(1, %r); import numpy as np; "
                "from filter_error_start import fit_all; "
                "fl = json.load(open(%r)); "
                "fl = [{k: (np.asarray(v) if k in ('t','u','z','forces') else v) "
                "for k, v in f.items()} for f in fl]; print(json.dumps(fit_all(fl)))"
                % (tmp, str(ROOT / "benchmarks"), str(data)))
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              env=env, cwd=tmp)
        if proc.returncode:
            raise SystemExit(proc.stderr[-2000:])
        return json.loads(proc.stdout.strip().splitlines()[-1])


def _wilson(k: int, n: int) -> str:
    if n == 0:
        return "-"
    z, p = 1.96, k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return f"[{100 * max(0, c - h):.0f}, {100 * min(1, c + h):.0f}] %"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=12, help="flights per vehicle")
    ap.add_argument("--before", default="7ae4ff9",
                    help="the commit whose filter error is 'before' (its own start and gain)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" /
                                         "filter_error_start.md"))
    args = ap.parse_args(argv)
    prov = provenance()
    flights = [flight(name, seed) for name in ("flapper-unstable", "delfly-closed-loop")
               for seed in range(args.seeds)]
    after = fit_all(flights)
    before = _before(args.before, flights)
    lines = [f"# Filter error on closed-loop flights: before ({args.before}) and after\n",
             f"{args.seeds} flights per vehicle, 20 s at 100 Hz, closed loop (LQR pitch "
             "controller, a 3211 on the reference), turbulence and measurement noise; "
             "`fwid.fit(..., method='filter-error')` with its defaults. Intervals: 95 % "
             "Wilson.\n",
             "| vehicle | true oscillatory mode | converged before | converged after | "
             "median wn error after (converged) |", "|---|---|---|---|---|"]
    for name in ("flapper-unstable", "delfly-closed-loop"):
        idx = [i for i, f in enumerate(flights) if f["name"] == name]
        eig = np.array([complex(*e) for e in flights[idx[0]]["eig"]])
        osc = eig[np.abs(eig.imag) > 1e-9][0]
        kb = sum(before[i]["converged"] for i in idx)
        ka = sum(after[i]["converged"] for i in idx)
        errs = [abs(after[i]["wn"] / abs(osc) - 1) for i in idx
                if after[i]["converged"] and after[i]["wn"]]
        med = f"{100 * np.median(errs):.1f} %" if errs else "-"
        lines.append(f"| {name} | {osc.real:+.2f} +- {abs(osc.imag):.2f}j 1/s | "
                     f"{kb}/{len(idx)} {_wilson(kb, len(idx))} | "
                     f"{ka}/{len(idx)} {_wilson(ka, len(idx))} | {med} |")
    errors = sorted({r["error"] for r in before + after if "error" in r})
    if errors:
        lines += ["", "Errors raised (counted as not converged):", ""]
        lines += [f"- {e}" for e in errors]
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(markdown(text, prov))
    print(text)


if __name__ == "__main__":
    main()
