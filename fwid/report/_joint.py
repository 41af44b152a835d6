"""The `joint_vs_individual` block of `report.json` and its terminal line: does a joint fit
validate better on held-out flights than the individual fits?"""

from __future__ import annotations

from ..identification._joint import JointComparison
from ..validate._modes import eigenvalues, modes
from ._identification import modes_spread


def joint_report(comparison: JointComparison) -> dict:
    """The `joint_vs_individual` block of `report.json` (`fwid identify --joint --validate`)."""
    c = comparison
    ind = [modes(eigenvalues(f.model, c.individual.consts)) for f in c.individual.fits]
    return {
        "training_flights": list(c.joint.flights),
        "outputs": list(c.joint.model.outputs),
        "score": "mean over the outputs of rms_pct (RMS as % of the measured range), "
                 "biases re-estimated on each held-out flight",
        "held_out": c.held_out,
        "summary": c.summary,
        "modes": {"joint": c.joint.modes, "individual_spread": modes_spread(ind)},
    }


def joint_summary(comparison: JointComparison) -> str:
    """One line for the terminal: which validates better, by how much."""
    s = comparison.summary
    better = {"joint": "the joint model validates better",
              "individual": "the individual models validate better",
              "tie": "neither validates clearly better"}[s["verdict"]]
    return (f"joint vs individual on {s['held_out_flights']} held-out flight(s): {better} "
            f"(held-out error ratio joint/individual {s['ratio']:.3f}, joint lower on "
            f"{s['joint_better_on']} of {s['held_out_flights']}; vs the mean model "
            f"{s['ratio_to_mean_model']:.3f})")
