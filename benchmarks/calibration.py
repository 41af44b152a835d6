"""Are fwid's standard deviations calibrated? Many simulated flights, full pipeline.

    python benchmarks/calibration.py --seeds 40 --out benchmarks/results/calibration.json

For each seed a noisy DelFly-like flight is simulated (flapping, elevator/rudder ripple,
sensor noise, reconstructed forces), cycle-averaged at 5 Hz and fitted (fwid.identify). The
script counts how often the true parameter lies within 2 sigma, for the reported `std`
(Cramer-Rao corrected for coloured residuals) and for the plain Cramer-Rao `std_cr`, and
the error of the oscillatory mode's eigenvalue.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import fwid
from fwid import synth
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


def oscillatory(eigs):
    eigs = np.asarray(eigs)
    return eigs[np.argmax(eigs.imag)]


def run(axis: str, seeds: int) -> dict:
    truth = synth.DELFLY.params()
    true_osc = oscillatory(synth.DELFLY.eigenvalues(axis))
    names = list(fwid.models.TABLE1 if axis == "lon" else fwid.models.TABLE4)
    z, zcr, osc_err = [], [], []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        for s in range(seeds):
            path = synth.write_flights(Path(d) / str(s), n_flights=1, axis=axis, seed=1000 + s)[0]
            ident = fwid.identify([fwid.load_flight(path)], axis)
            f = ident.fit
            idx = [f.names.index(k) for k in names]
            est = np.asarray(f.theta)[idx]
            tru = np.array([truth[k] for k in names])
            z.append((est - tru) / np.asarray(f.std)[idx])
            zcr.append((est - tru) / np.asarray(f.std_cr)[idx])
            osc_err.append(abs(oscillatory(ident.eigenvalues) - true_osc) / abs(true_osc))
    z, zcr = np.array(z), np.array(zcr)
    return {
        "axis": axis, "seeds": seeds, "parameters": names,
        "within_2sigma_std": float(np.mean(np.abs(z) < 2)),
        "within_2sigma_std_cr": float(np.mean(np.abs(zcr) < 2)),
        "rms_z_std": float(np.sqrt(np.mean(z**2))),
        "rms_z_std_cr": float(np.sqrt(np.mean(zcr**2))),
        "per_parameter_within_2sigma_std": dict(zip(names, np.mean(np.abs(z) < 2, 0).tolist())),
        "oscillatory_mode_rel_error": {"median": float(np.median(osc_err)),
                                       "max": float(np.max(osc_err))},
        "wall_s": time.perf_counter() - t0,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--axes", default="lon,lat")
    ap.add_argument("--out", default="benchmarks/results/calibration.json")
    args = ap.parse_args(argv)
    results = [run(a, args.seeds) for a in args.axes.split(",")]
    for r in results:
        print(f"{r['axis']}: truth within 2 sigma {100 * r['within_2sigma_std']:.0f} % with std, "
              f"{100 * r['within_2sigma_std_cr']:.0f} % with plain Cramer-Rao; RMS z "
              f"{r['rms_z_std']:.2f} / {r['rms_z_std_cr']:.2f}; oscillatory mode error median "
              f"{100 * r['oscillatory_mode_rel_error']['median']:.2f} %, max "
              f"{100 * r['oscillatory_mode_rel_error']['max']:.2f} % ({r['seeds']} seeds)")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(_provenance.json_text(results, indent=2))


if __name__ == "__main__":
    main()
