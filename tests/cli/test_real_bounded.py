"""A real flight (`../shared/realdata`, see its SOURCES.md) whose filter-error fit fails:
whatever the fit gives, the summary prints no number beyond what its quantity can be, and the
failure names one next step the command line has. Skipped when the recordings are absent."""

import csv
import json
import re
from pathlib import Path

import pytest

from fwid.cli import main
from fwid.cli._parser import parser

from ..reconstruction.helpers import REAL

TAKE = REAL / "fd_model_tuning_level_flight_1.csv.gz"
MAP = Path(__file__).resolve().parents[2] / "docs" / "guide" / "flapper.toml"
VEHICLE = {"mass": 0.103, "Ix": 3.2e-4, "Iy": 4.9e-4, "Iz": 3.5e-4, "Ixz": 0.0, "g": 9.81}

pytestmark = pytest.mark.skipif(not TAKE.exists(),
                                reason=f"real recordings not found beside the repository ({REAL})")


def _airborne(flights: Path, out: Path) -> Path:
    """The flight from 12 s after its start to 8 s before its end (in the air)."""
    out.mkdir()
    (out / "vehicle.json").write_text((flights / "vehicle.json").read_text())
    rows = list(csv.reader((flights / "fd_model_tuning_level_flight_1.csv").open()))
    t = [float(r[0]) for r in rows[1:]]
    keep = [r for r, x in zip(rows[1:], t) if t[0] + 12 <= x <= t[-1] - 8]
    path = out / "level_flight_1.csv"
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows([rows[0], *keep])
    return path


def test_a_failed_real_fit_prints_bounded_numbers_and_one_next_step(tmp_path, capsys):
    raw = tmp_path / "raw"
    raw.mkdir()
    (raw / TAKE.name).symlink_to(TAKE)
    (raw / "vehicle.json").write_text(json.dumps(VEHICLE))
    assert main(["reconstruct", str(raw), "--map", str(MAP), "--out", str(tmp_path / "fl"),
                 "--max-dropout", "1", "--no-figures", "--quiet"]) == 0
    flight = _airborne(tmp_path / "fl", tmp_path / "air")
    capsys.readouterr()
    rc = main(["identify", str(flight), "--model", "lon", "--method", "filter-error",
               "--quiet"])
    out, err = capsys.readouterr()
    numbers = [abs(float(x)) for x in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?", out)]
    assert max(numbers) <= 1e6, out
    if rc == 1:  # the fit failed: the one next step is an option of fwid identify
        step = err.strip().splitlines()[-1].rsplit("next: ", 1)[1]
        flag = step.split()[0]
        ident = next(a for a in parser()._actions if hasattr(a, "choices") and a.choices
                     and "identify" in a.choices).choices["identify"]
        assert flag in {o for a in ident._actions for o in a.option_strings}, step
        assert not step.startswith("--method filter-error"), step
    else:
        assert rc == 0, err
