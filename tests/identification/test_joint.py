"""Several flights through `fwid identify`: one fit per flight (batched), the joint fit, and
the joint-vs-individual comparison on held-out flights."""

import contextlib
import io
import json

import numpy as np
import pytest

import fwid
from fwid.cli import main
from fwid.synth import DELFLY, lon_matrices


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("flights")
    assert main(["simulate", str(out), "--flights", "5", "--seed", "11"]) == 0
    return out


def _identify(folder, out, *extra):
    """The report, with what the terminal showed under the key `_terminal`."""
    train = [str(folder / f"lon_{i}.csv") for i in range(3)]
    test = [str(folder / f"lon_{i}.csv") for i in (3, 4)]
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["identify", *train, "--model", "lon", "--validate", *test, "--out",
                     str(out), "--quiet", *extra]) == 0
    return {**json.loads((out / "report.json").read_text()), "_terminal": text.getvalue()}


@pytest.fixture(scope="module")
def each(folder, tmp_path_factory):
    return _identify(folder, tmp_path_factory.mktemp("each"))


@pytest.fixture(scope="module")
def joint(folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("joint")
    return _identify(folder, out, "--joint"), out


def _true_wn():
    lam = np.linalg.eigvals(lon_matrices(DELFLY)[0])
    return np.abs(lam[np.abs(lam.imag) > 0][0])


def test_per_flight_fits_and_their_spread(each):
    """Without --joint: one fit per flight (per_flight), the top level their mean,
    and the modes' spread over the flights (Figures 8 and 11)."""
    per = each["per_flight"]
    assert [p["flight"] for p in per] == ["lon_0.csv", "lon_1.csv", "lon_2.csv"]
    mq = [p["parameters"]["Mq"]["value"] for p in per]
    assert each["parameters"]["Mq"]["value"] == pytest.approx(np.mean(mq), rel=1e-12)
    assert each["parameters"]["Mq"]["std"] == pytest.approx(np.std(mq, ddof=1), rel=1e-12)
    spread = each["modes_spread"]["oscillatory"]
    wn = [next(m["wn"] for m in p["modes"] if m["kind"] == "oscillatory") for p in per]
    assert spread["wn_mean"] == pytest.approx(np.mean(wn), rel=1e-12)
    assert spread["wn_mean"] == pytest.approx(_true_wn(), rel=0.02)  # Table 3's mode
    assert "joint_vs_individual" not in each


def test_joint_fit_has_one_parameter_set_and_biases_per_flight(joint):
    report, out = joint
    assert report["joint"] is True and "per_flight" not in report
    assert {f"bq@{i}" for i in range(3)} <= set(report["local_parameters"])
    osc = [m for m in report["modes"] if m["kind"] == "oscillatory"][0]
    assert osc["wn"] == pytest.approx(_true_wn(), rel=0.02)
    assert (out / "poles.png").stat().st_size > 0


def test_joint_vs_individual_block_is_consistent(joint, each):
    """The comparison's numbers recomputed from its own rows, and its individual models are
    those of the run without --joint (same flights, same fits)."""
    c = joint[0]["joint_vs_individual"]
    rows = c["held_out"]
    assert [r["flight"] for r in rows] == ["lon_3.csv", "lon_4.csv"]
    for r in rows:
        assert r["individual_best"] <= r["individual_median"] <= r["individual_worst"]
        assert r["joint"] > 0 and r["best_individual"] in c["training_flights"]
    s = c["summary"]
    ratio = np.median([r["joint"] / r["individual_median"] for r in rows])
    assert s["ratio"] == pytest.approx(ratio, rel=1e-12)
    assert s["joint_better_on"] == sum(r["joint"] < r["individual_median"] for r in rows)
    expected = "joint" if ratio < 0.98 else "individual" if ratio > 1.02 else "tie"
    assert s["verdict"] == expected
    wn_each = each["modes_spread"]["oscillatory"]["wn_mean"]
    assert c["modes"]["individual_spread"]["oscillatory"]["wn_mean"] == pytest.approx(
        wn_each, rel=1e-9)


def test_scores_are_those_of_the_plain_validation(joint, each):
    """The comparison's joint and mean-model scores are the held-out metrics that the runs
    with and without --joint report for the same flights (validation_flights)."""
    c = joint[0]["joint_vs_individual"]

    def score(metrics):
        return np.mean([metrics[k]["rms_pct"] for k in c["outputs"]])

    for r, vj, ve in zip(c["held_out"], joint[0]["validation_flights"],
                         each["validation_flights"]):
        assert r["flight"] == vj["flight"] == ve["flight"]
        assert r["joint"] == pytest.approx(score(vj["metrics"]), rel=1e-9)
        assert r["mean_model"] == pytest.approx(score(ve["metrics"]), rel=1e-9)


def test_held_out_scores_without_identify_validation(joint, folder):
    """Given a joint identification made without held-out flights, the comparison simulates
    the joint model on them itself: the same scores as identify's own validation (above)."""
    flights = fwid.load_flights(*(folder / f"lon_{i}.csv" for i in range(5)))
    plain = fwid.identify(flights[:3], "lon", joint=True)
    assert plain.validation == []
    c = fwid.compare_joint(flights[:3], "lon", validate=flights[3:], joint=plain)
    for r, ref in zip(c.held_out, joint[0]["joint_vs_individual"]["held_out"]):
        assert r["joint"] == pytest.approx(ref["joint"], rel=1e-9)
        assert r["mean_model"] == pytest.approx(ref["mean_model"], rel=1e-9)


def test_needs_two_training_flights_and_held_out_ones(folder):
    flights = fwid.load_flights(folder / "lon_0.csv", folder / "lon_1.csv")
    with pytest.raises(fwid.InputError, match="at least two"):
        fwid.compare_joint(flights[:1], "lon", validate=flights[1:])
    with pytest.raises(fwid.InputError, match="held-out"):
        fwid.compare_joint(flights, "lon", validate=[])


def test_results_print_as_short_summaries(tmp_path):
    """Printing a result gives one short line with the headline numbers, not its arrays."""
    folder = tmp_path / "f"
    assert main(["simulate", str(folder), "--flights", "2", "--seed", "5"]) == 0
    flights = fwid.load_flights(folder)
    ident = fwid.identify(flights[:1], "lon", validate=flights[1:])
    for obj in (ident, ident.estimation[0], ident.validation[0]):
        text = repr(obj)
        assert "\n" not in text and len(text) < 400 and "array" not in text, text
    assert "1/1 converged" in repr(ident) and "lon_1.csv" in repr(ident)
    assert "rms as % of range: q" in repr(ident.validation[0])


def test_missing_force_columns_are_said(tmp_path):
    """A flight without X, Z, M: the states are fitted, and a warning says what changed."""
    import csv

    folder = tmp_path / "f"
    assert main(["simulate", str(folder), "--flights", "1", "--seed", "6"]) == 0
    rows = list(csv.reader((folder / "lon_0.csv").open()))
    keep = [i for i, c in enumerate(rows[0]) if c not in ("X", "Y", "Z", "L", "M", "N")]
    with (folder / "lon_0.csv").open("w", newline="") as fh:
        csv.writer(fh).writerows([[r[i] for i in keep] for r in rows])
    with pytest.warns(UserWarning, match=r"lon_0\.csv: no force/moment columns X Z M; the lon "
                                         r"model is fitted to the states alone"):
        ident = fwid.identify(fwid.load_flights(folder), "lon")
    assert ident.fit.converged and "M" not in ident.estimation[0].metrics


# ------------------------------------------------------------------ the spread on the terminal


def _rows(text: str, title: str) -> dict:
    """The spread table under `title`: {label: [mean, std, min, max]}."""
    lines = text[text.index(title):].splitlines()[2:]
    rows = {}
    for ln in lines:
        if not ln.strip():
            break
        *label, a, b, c, d = ln.split()
        rows[" ".join(label)] = [float(a), float(b), float(c), float(d)]
    return rows


def _check(rows: dict, spread: dict):
    osc = spread["oscillatory"]
    for key, label in (("wn", "wn [rad/s]"), ("zeta", "zeta")):
        want = [osc[f"{key}_{s}"] for s in ("mean", "std", "min", "max")]
        np.testing.assert_allclose(rows[label], want, rtol=1e-3, atol=1e-12)
    assert osc["wn_min"] <= osc["wn_mean"] <= osc["wn_max"]
    for j, tau in enumerate(spread["aperiodic_tau"]):
        np.testing.assert_allclose(rows[f"tau {j + 1} [s]"],
                                   [tau[s] for s in ("mean", "std", "min", "max")], rtol=1e-3)


def test_spread_of_individual_fits_printed(each):
    """Several flights fitted one by one: the terminal shows the modes' spread, with the
    numbers of report.json."""
    spread = each["modes_spread"]
    assert spread["flights"] == 3
    _check(_rows(each["_terminal"], "mode spread over 3 flights (each fitted alone):"), spread)


def test_spread_with_joint_and_validate_printed(joint):
    """--joint --validate: the individual fits' spread beside the joint model's modes."""
    report = joint[0]
    spread = report["joint_vs_individual"]["modes"]["individual_spread"]
    _check(_rows(report["_terminal"], "mode spread over the 3 training flights, each fitted "
                 "alone"), spread)


def test_identify_passes_the_noise_model_to_every_fit(folder):
    """`noise` reaches `fwid.fit` in both forms of `identify`: the fits report the R they
    were made with."""
    flights = fwid.load_flights(*[folder / f"lon_{i}.csv" for i in range(3)])
    joint = fwid.identify(flights, "lon", joint=True, noise="diagonal")
    each = fwid.identify(flights, "lon", noise="full")
    assert [f.noise for f in joint.fits] == ["diagonal"]
    assert [f.noise for f in each.fits] == ["full"] * 3
    with pytest.raises(ValueError, match="noise must be one of"):
        fwid.identify(flights, "lon", noise="white")
