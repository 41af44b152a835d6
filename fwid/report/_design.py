"""The files of `fwid design` (the test-input format): `input.csv`, `design.json` and the figure
of the input, the predicted response and the predicted standard deviations side by side."""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np

from ._json import _default_mode, write_json, write_text

#: The other axis's control, written as a column of zeros when it is held.
_OTHER = {"de": "dr", "dr": "de"}


def input_csv(design) -> str:
    """`t` (s, from 0) and the control column (rad, perturbation from trim); the other
    axis's control as zeros when it is held."""
    cols = [design.control]
    other = _OTHER.get(design.control)
    held = design.limits.get("other_control_held") and other is not None
    if held:
        cols.append(other)
    rows = [",".join(["t", *cols])]
    for t, u in zip(design.t, design.u):
        rows.append(",".join([f"{t:.6f}", f"{u:.10g}"] + (["0"] if held else [])))
    return "\n".join(rows) + "\n"


def plot_design(design):
    """Input, predicted response (the attitude and every output, normalised), and the
    predicted standard deviations (designed vs 3211), side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    ax[0].plot(design.t, np.degrees(design.u), label="designed")
    ax[0].plot(design.t, np.degrees(design.u_3211), "--", label="3211")
    ax[0].set(xlabel="t [s]", ylabel=f"{design.control} [deg]", title="input")
    ax[0].legend()
    for i, name in enumerate(design.outputs):
        ax[1].plot(design.t, design.response[:, i], label=name)
    ax[1].set(xlabel="t [s]", ylabel="perturbation (SI)", title="predicted response")
    ax[1].legend(fontsize=8)
    names = list(design.vehicle_names)
    idx = [design.names.index(k) for k in names]
    x = np.arange(len(names))
    ax[2].bar(x - 0.2, design.std_3211[idx] / np.abs(design.std_3211[idx]), 0.4, label="3211")
    ax[2].bar(x + 0.2, design.std[idx] / design.std_3211[idx], 0.4, label="designed")
    ax[2].set_xticks(x, names, rotation=90)
    ax[2].set(ylabel="predicted std / std of the 3211", title="predicted standard deviations")
    ax[2].legend()
    fig.tight_layout()
    return fig


def write_design(design, out: Path) -> list[str]:
    """Write `input.csv`, `design.json` and `design.png` into `out`, each atomically."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "input.csv", input_csv(design))
    write_json(out / "design.json", design.to_json())
    _save_png(plot_design(design), out / "design.png")
    return ["input.csv", "design.json", "design.png"]


def plot_discrimination(d, control: str, names: tuple[str, str]):
    """The discriminating input and the two models' predicted outputs (normalised)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(d.outputs)
    fig, ax = plt.subplots(1, n + 1, figsize=(4 * (n + 1), 3.6))
    ax[0].plot(d.t, np.degrees(d.u), label="designed")
    ax[0].plot(d.t, np.degrees(d.u_3211), "--", label="3211")
    ax[0].set(xlabel="t [s]", ylabel=f"{control} [deg]", title="input")
    ax[0].legend()
    for i, name in enumerate(d.outputs):
        ax[i + 1].plot(d.t, d.response_a[:, i], label=names[0])
        ax[i + 1].plot(d.t, d.response_b[:, i], "--", label=names[1])
        ax[i + 1].set(xlabel="t [s]", title=f"predicted {name}")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    return fig


def _save_png(fig, path: Path) -> None:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    with os.fdopen(fd, "wb") as fh:
        fh.write(buf.getvalue())
    os.chmod(tmp, _default_mode())
    os.replace(tmp, path)


def discrimination_csv(d, control: str) -> str:
    """A discriminating input in the test-input format: `t` (s) and the control (rad,
    perturbation from trim)."""
    rows = ["t," + control] + [f"{t:.6f},{u:.10g}" for t, u in zip(d.t, d.u)]
    return "\n".join(rows) + "\n"


def write_discrimination(d, control: str, info: dict, out: Path) -> list[str]:
    """`input.csv`, `design.json` (the pair, the criterion, the limits, what was held at
    zero) and `design.png` of `fwid design --discriminate`."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "input.csv", discrimination_csv(d, control))
    write_json(out / "design.json", {"discriminate": info, "control": control, **d.to_json()})
    names = tuple(p["effect"] for p in info["pair"])
    _save_png(plot_discrimination(d, control, names), out / "design.png")
    return ["input.csv", "design.json", "design.png"]
