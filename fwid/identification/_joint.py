"""Joint or individual fits: which validates better on held-out flights.

The paper fits each flight on its own and notes that its datasets were short and the
aperiodic modes scattered from flight to flight. A joint fit shares one parameter set
between the flights (each keeps its own initial state and bias terms), so every parameter
sees all the data. Whether that is the better model is an empirical question, answered here
on flights that neither fit has seen.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._errors import InputError
from ..data._flight import Flight
from ..simulation._averaged import averaged
from ._cycle_averaged import Identification, identify
from ._flight_fit import evaluate

# A difference in the held-out error smaller than this (relative) is called a tie.
TIE = 0.02


def _score(metrics: dict, outputs: Sequence[str]) -> float:
    """One number per flight and model: the mean over the outputs of the RMS error as % of
    the output's measured range (`rms_pct`), so outputs of different units weigh alike."""
    return float(np.mean([metrics[k]["rms_pct"] for k in outputs]))


@dataclass(frozen=True, repr=False)
class JointComparison:
    """What [`fwid.compare_joint`][] found.

    **Fields:**
    - `joint`, `individual`: the two identifications (`fwid.identify` with and without
      `joint`) from the same training flights.
    - `held_out`: per held-out flight, the score (mean `rms_pct` over the outputs) and the
      RMS per output of the joint model, of the mean of the individual estimates (the model
      `identify` reports without `joint`), and of every individual model (median, best,
      worst); biases re-estimated on the held-out flight in every case.
    - `summary`: `ratio` (median over held-out flights of the joint score over the median
      individual score; below 1: the joint model is better), `ratio_to_mean_model`,
      `joint_better_on` (held-out flights where the joint score is the lower), `verdict`
      (`"joint"`, `"individual"` or `"tie"`, within `TIE`).
    """

    joint: Identification
    individual: Identification
    held_out: list[dict]
    summary: dict

    def __repr__(self) -> str:
        s = self.summary
        return (f"JointComparison(verdict={s['verdict']!r}, ratio joint/individual "
                f"{s['ratio']:.3f}, joint better on {s['joint_better_on']} of "
                f"{s['held_out_flights']} held-out flights)")



def compare_joint(
    flights: Sequence[Flight],
    model="lon",
    *,
    validate: Sequence[Flight],
    joint: Identification | None = None,
    individual: Identification | None = None,
    cutoff: float = 5.0,
    noise_cutoff: float = 40.0,
    progress: bool = False,
    prior=None,
    bounds=None,
    method: str = "output-error",
    noise: str = "auto",
) -> JointComparison:
    """Fit `model` to `flights` jointly and one by one, and score both on `validate`.

    Every model is simulated on every held-out flight with its bias terms re-estimated there
    (the flight's own trim errors), the rest fixed; the score is the mean over the outputs of
    the RMS error as % of the output's range. The joint model is compared with the median
    individual model (a typical single-flight fit) and with the mean of the individual
    estimates.

    **Arguments:** as [`fwid.identify`][]; `joint` and `individual` are identifications
    already made from the same flights (with and without `joint`), reused instead of fitted
    again.

    **Returns:** a [`fwid.JointComparison`][].
    """
    flights, validate = list(flights), list(validate)
    if len(flights) < 2:
        raise InputError("comparing a joint fit with individual fits needs at least two "
                         f"training flights (got {len(flights)})")
    if not validate:
        raise InputError("comparing a joint fit with individual fits needs held-out flights "
                         "(validate=...)")
    kw = dict(validate=validate, cutoff=cutoff, noise_cutoff=noise_cutoff, progress=progress,
              prior=prior, bounds=bounds, method=method, noise=noise)
    joint = joint or identify(flights, model, joint=True, **kw)
    individual = individual or identify(flights, model, joint=False, **kw)
    outputs = list(joint.model.outputs)
    names = [f.name for f in validate]

    def validated(ident):  # identify's own validation of its summary model, if on these flights
        return ident.validation if [v.name for v in ident.validation] == names else None

    vj, vm = validated(joint), validated(individual)
    rows = []
    for i, f in enumerate(validate):
        exp = averaged(f, joint.model, cutoff, noise_cutoff)

        def on_flight(m, exp=exp, name=f.name):
            return evaluate(m, exp, name).metrics

        mj = vj[i].metrics if vj else on_flight(joint.model)
        mm = vm[i].metrics if vm else on_flight(individual.model)
        mi = [on_flight(fr.model) for fr in individual.fits]
        si = np.array([_score(m, outputs) for m in mi])
        order = np.argsort(si)
        rows.append({
            "flight": f.name,
            "joint": _score(mj, outputs), "mean_model": _score(mm, outputs),
            "individual_median": float(np.median(si)), "individual_best": float(si.min()),
            "individual_worst": float(si.max()),
            "rms": {"joint": {k: mj[k]["rms"] for k in outputs},
                    "mean_model": {k: mm[k]["rms"] for k in outputs},
                    "individual_median": {k: float(np.median([m[k]["rms"] for m in mi]))
                                          for k in outputs}},
            "best_individual": individual.flights[order[0]],
        })
    ratio = float(np.median([r["joint"] / r["individual_median"] for r in rows]))
    ratio_mean = float(np.median([r["joint"] / r["mean_model"] for r in rows]))
    verdict = "joint" if ratio < 1 - TIE else "individual" if ratio > 1 + TIE else "tie"
    summary = {
        "ratio": ratio, "ratio_to_mean_model": ratio_mean,
        "joint_better_on": int(sum(r["joint"] < r["individual_median"] for r in rows)),
        "held_out_flights": len(rows), "verdict": verdict,
    }
    return JointComparison(joint=joint, individual=individual, held_out=rows, summary=summary)
