"""ATTAS short-period test case 11 (Jategaonkar, Flight Vehicle System Identification, 2nd ed.)
fitted with fwid in a few lines of user code, compared with the book's published OEM values.

    python benchmarks/attas_tc11.py --json OUT.json [--lateral]

Writes `{"Z0": {"value": .., "std": ..}, ..}` for `Z0 Za Zq Zde M0 Ma Mq Mde` (and, with
`--lateral`, the test case 3 estimates under the key "tc3"). The data are read from
`../shared/flightdata/jategaonkar_fvsysid2` (or `$FWID_FLIGHTDATA`), never copied.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import jax.numpy as jnp

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fwid  # noqa: E402
from cases.attas import (  # noqa: E402
    TC3_BOOK_OEM_L0_CORRECTED,
    TC3_NAMES,
    TC3_THETA0,
    TC11_BOOK_OEM,
    TC11_NAMES,
    TC11_THETA0,
    load_attas_tc3,
    load_attas_tc11,
)
import _provenance  # noqa: E402  (benchmarks/: the results files' provenance)


def short_period(x, u, p, c):
    """alpha' = Z0 + Za alpha + (1 + Zq) q + Zde de;  q' = M0 + Ma alpha + Mq q + Mde de."""
    alpha, q = x
    de = u[0]
    return jnp.stack([
        p["Z0"] + p["Za"] * alpha + (1.0 + p["Zq"]) * q + p["Zde"] * de,
        p["M0"] + p["Ma"] * alpha + p["Mq"] * q + p["Mde"] * de,
    ])


def roll_yaw(x, u, p, c):
    """p' = Lp p + Lr r + Lda da + Ldr dr + Lbeta beta + L0;  r' likewise with N."""
    pp, r = x
    da, dr, beta = u
    return jnp.stack([
        p["Lp"] * pp + p["Lr"] * r + p["Lda"] * da + p["Ldr"] * dr + p["Lbeta"] * beta + p["L0"],
        p["Np"] * pp + p["Nr"] * r + p["Nda"] * da + p["Ndr"] * dr + p["Nbeta"] * beta + p["N0"],
    ])


def fit_tc11(folder=None, *, start="least-squares"):
    """Both elevator manoeuvres together, each integrated from its own first sample."""
    model = fwid.GreyBoxModel(short_period, states=("alpha", "q"), inputs=("de",),
                              params=dict(zip(TC11_NAMES, TC11_THETA0)), name="attas-tc11")
    records = load_attas_tc11(folder)
    exps = [fwid.Experiment(r["t"], r["u"], r["z"]) for r in records]
    return fwid.fit(model, exps, names=[r["name"] for r in records], start=start)


def fit_tc3(folder=None, *, start="least-squares"):
    model = fwid.GreyBoxModel(roll_yaw, states=("p", "r"), inputs=("da", "dr", "beta"),
                              params=dict(zip(TC3_NAMES, TC3_THETA0)), name="attas-tc3")
    records = load_attas_tc3(folder)
    exps = [fwid.Experiment(r["t"], r["u"], r["z"]) for r in records]
    return fwid.fit(model, exps, names=[r["name"] for r in records], start=start)


def _as_dict(result, names, book):
    out = {}
    for i, k in enumerate(names):
        j = result.names.index(k)
        v = float(result.theta[j])
        out[k] = {"value": v, "std": float(result.std[j]), "std_cr": float(result.std_cr[j]),
                  "book": float(book[i]), "rel_diff_pct": 100 * (v - book[i]) / abs(book[i])}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", required=True, help="where to write the estimates")
    ap.add_argument("--lateral", action="store_true", help="also test case 3 (lateral)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    r11 = fit_tc11()
    out = _as_dict(r11, TC11_NAMES, TC11_BOOK_OEM)
    wall = time.perf_counter() - t0
    print(f"ATTAS test case 11 (short period), fwid output-error fit in {wall:.1f} s "
          f"(first call, compilation included)")
    print(f"{'param':<7}{'fwid':>12}{'std':>10}{'book':>12}{'diff %':>8}")
    for k, v in out.items():
        print(f"{k:<7}{v['value']:>12.5g}{v['std']:>10.2g}{v['book']:>12.5g}"
              f"{v['rel_diff_pct']:>8.2f}")
    if args.lateral:
        r3 = fit_tc3()
        out["tc3"] = _as_dict(r3, TC3_NAMES, TC3_BOOK_OEM_L0_CORRECTED)
        print("\nATTAS test case 3 (lateral, p and r)")
        for k, v in out["tc3"].items():
            print(f"{k:<7}{v['value']:>12.5g}{v['std']:>10.2g}{v['book']:>12.5g}"
                  f"{v['rel_diff_pct']:>8.2f}")
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(_provenance.json_text(out, indent=2))
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
