"""The gap in the simulated states: the diagnosed effect put into the EOM (`_augment.py`),
re-fitted by output error on the training flights, simulated on the test flights."""

import json
import types

import jax.numpy as jnp
import numpy as np
import pytest

import fwid
from fwid.decomposition import decompose
from fwid.diagnosis._augment import augment
from fwid.diagnosis._simulation import simulation_gap


def test_an_actuator_lag_in_the_eom_closes_the_simulated_gap(effect_flights, tmp_path):
    """4 + 4 flights with an actuator lag: the diagnosis names it, and with its lag state in
    the EOM the test flights' simulated states are at least 20 % closer to the measured ones;
    the augmented model is returned with standard deviations."""
    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=4, n_test=4))
    d = fwid.diagnose(train, test)
    assert d.verdict == "actuator-dynamics"
    sim = d.simulation
    assert sim["effects"] == ["actuator-dynamics"] and sim["states"] == ["q", "u", "w", "theta"]
    assert sim["shrink_pct"] >= 20.0, sim
    for s in sim["states"]:
        assert sim["test_rms_after"][s] < sim["test_rms_before"][s]
    aug = d.models.augmented
    assert aug is not None and aug.model.inputs == ("de_eff",)
    table = aug.fits[0].table()
    assert all(np.isfinite(table[k]["std"]) and table[k]["std"] > 0 for k in ("Mde", "Zde"))
    assert d.to_json()["simulation"]["shrink_pct"] == sim["shrink_pct"]
    # which fit stopped at its step limit is said, and the caution points the right way
    assert sim["converged_baseline"] == all(f.converged for f in d.models.baseline.fits)
    assert sim["converged_augmented"] == all(f.converged for f in aug.fits)
    assert sim["converged"] == (sim["converged_baseline"] and sim["converged_augmented"])
    from fwid.report import diagnosis_summary

    cautions = {(True, True): None, (False, True): "the shrink may be overstated",
                (True, False): "the shrink may be understated", (False, False): "rough"}
    for flags, words in cautions.items():
        sim.update(converged=all(flags), converged_baseline=flags[0],
                   converged_augmented=flags[1])
        text = diagnosis_summary(d)
        assert ("CAUTION" in text) == (words is not None)
        assert words is None or words in text
    # what `fwid diagnose --out` writes: the figures and the model to carry on with
    from fwid.report import write_diagnosis

    written = write_diagnosis(d, tmp_path)
    assert set(written) == {"diagnosis.json", "gap_map.png", "gap_sim.png",
                            "augmented_model.json", "augmented_parameters.csv"}
    rep = json.loads((tmp_path / "augmented_model.json").read_text())
    assert rep["model"] == "lon+actuator-dynamics" and rep["parameters"]["Mde"]["std"] > 0
    assert "Mde," in (tmp_path / "augmented_parameters.csv").read_text()
    # the diagnosed time constant travels with the model, and `prepare` applies it anew
    assert "first-order lag, tau = " in rep["prepared_inputs"]["de_eff"]
    assert "de_eff" in d.models.prepare(train[0]).columns
    assert json.loads((tmp_path / "diagnosis.json").read_text())["simulation"]["effects"] == [
        "actuator-dynamics"]


def test_no_shrink_from_an_effect_that_is_not_there(effect_flights):
    """Clean flights with smooth terms forced into the model anyway (each state's two
    smoothest spline components and their products: 27 more free derivatives): the simulated
    gap on the test flights shows no gain (no over-fitting on the training flights passes for
    an effect) and moves little (6 % worse when written, with 4 training flights)."""
    from fwid.diagnosis._catalogue._smooth import smooth_basis
    from fwid.diagnosis._catalogue.nonlinear_aero import Terms
    from fwid.diagnosis._signals import cycle_averaged

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "none", seed=6, n_train=4, n_test=4))
    slow = [cycle_averaged(f, ("u", "w", "q")) for f in train]
    bases = {x: smooth_basis(np.concatenate([s[x] for s in slow])) for x in ("u", "w", "q")}
    gap = simulation_gap(train, test, "lon", [("nonlinear-aero", Terms((0, 1, 2), 2, True,
                                                                       bases))])
    assert gap.augmented is not None and len(gap.augmented.model.free) == 16 + 27
    assert -10.0 < gap.summary["shrink_pct"] < 2.0, gap.summary


@pytest.mark.parametrize("axis", ["lon", "lat"])
def test_augmented_eom_adds_the_extra_loads_as_the_aerodynamic_ones(axis):
    """The augmented state equation equals the base one plus the extra loads mapped through
    the same EOM: checked against the base model with the extra load folded into a derivative
    (an independent route: a state derivative times the state)."""
    from fwid.diagnosis._catalogue._smooth import smooth_basis
    from fwid.diagnosis._catalogue.nonlinear_aero import Terms

    s0 = {"lon": "q", "lat": "p"}[axis]  # the first state: its smooth bend g adds g(s0)
    basis = smooth_basis(np.linspace(-1.0, 1.0, 500) ** 3)
    member = Terms(({"lon": 2, "lat": 1}[axis],), 1, bases={s0: basis})
    model, _, left = augment(axis, [("nonlinear-aero", member), ("lon-lat-coupling", None),
                                    ("flap-coupling", None)])
    assert left == ["flap-coupling"]
    base = fwid.longitudinal() if axis == "lon" else fwid.lateral()
    c = {"mass": 0.02, "Iy": 1e-4, "Ix": 2e-4, "Iz": 1.5e-4, "Ixz": 1e-5, "g": 9.81,
         "u0": 0.5, "w0": 0.1, "theta0": 0.3}
    c = {k: jnp.asarray(c[k]) for k in model.constants}
    x = jnp.array([0.1, 0.2, -0.3, 0.05])
    u = jnp.array([0.02] + [0.0] * (len(model.inputs) - 1))
    load = {"lon": "M", "lat": "L"}[axis]
    p = {k: jnp.asarray(v) for k, v in model.params.items()}
    p[f"{load}_{s0}1"] = jnp.asarray(0.7)
    pb = {k: jnp.asarray(v) for k, v in base.params.items()}
    g = float(basis(np.array([0.1]))[0, 0])  # scipy's piecewise cubic, numpy
    pb[f"{load}{s0}"] = pb[f"{load}{s0}"] + 0.7 * g / 0.1  # the same load, as a derivative
    np.testing.assert_allclose(model.f(x, u, p, c), base.f(x, u[:1], pb, c), rtol=1e-12)
    np.testing.assert_allclose(model.forces(x, u, p, c), base.forces(x, u[:1], pb, c),
                               rtol=1e-12)


def test_new_catalogue_entries_in_the_eom_read_their_prepared_columns(effect_flights):
    """`unsteady-aero`, `flap-frequency` and `time-offset` enter the EOM as extra inputs that
    `prepare` computes from the flight: per load, the lagging part of its quasi-steady load
    (the diagnosed derivatives on the cycle-averaged states, through a first-order lag
    computed independently here), acting on that load alone; the frequency's deviation
    from its median and its square; and the cycle-averaged control (what the diagnosis
    fitted on the loads) shifted earlier by the lead."""
    from scipy.signal import lfilter, lfilter_zi

    from fwid.diagnosis._catalogue.unsteady_aero import Lagging

    member = Lagging("lag", 0.05, {"X": {"w": 0.2, "q": 0.1}, "Z": {"u": -0.3, "q": 0.4},
                                   "M": {"u": 0.01, "w": -0.05}})
    model, prepare, left = augment("lon", [("time-offset", 0.03), ("unsteady-aero", member),
                                           ("flap-frequency", 0.0)])
    assert left == []
    assert model.inputs == ("de_eff", "X_lag", "Z_lag", "M_lag", "f_dev", "f_dev2")
    assert {"X_lag", "Z_lag", "M_lag", "Xf_dev", "Mf_dev2"} <= set(model.free)
    assert not {"MX_lag", "XM_lag", "ZM_lag"} & set(model.free)  # each load its own
    fl = prepare(fwid.load_flights(effect_flights("none", seed=0)[0])[0])
    slow = {x: np.asarray(decompose({x: np.asarray(fl[x]) - float(fl.trim_value(x))},
                                    fl.dt).averaged[x]) for x in ("u", "w")}
    qs = 0.01 * slow["u"] - 0.05 * slow["w"]
    a = np.exp(-fl.dt / 0.05)
    b = (0.5 * (1 - a), 0.5 * (1 - a))
    ref, _ = lfilter(b, (1, -a), qs, zi=lfilter_zi(b, (1, -a)) * qs[0])
    np.testing.assert_allclose(np.asarray(fl["M_lag"]), ref - qs, atol=1e-12)
    f = np.asarray(fl["f"])
    np.testing.assert_allclose(np.asarray(fl["f_dev2"]), (f - np.median(f)) ** 2, atol=1e-12)
    de = np.asarray(fl["de"]) - float(fl.trim_value("de"))
    slow = np.asarray(decompose({"de": de}, fl.dt).averaged["de"])  # as the loads saw it
    k = round(0.03 / fl.dt)
    np.testing.assert_allclose(np.asarray(fl["de_eff"])[:-k], slow[k:], atol=1e-9)


def test_the_drift_probe_in_the_eom_reads_the_elapsed_time(effect_flights):
    """`drift` (a trend common to all flights) enters as the time since the start per 10 s and
    its square, with a coefficient per load, as the probe fitted it."""
    model, prepare, left = augment("lon", [("drift", None)])
    assert left == [] and model.inputs == ("de", "time", "time2")
    assert {"Xtime", "Ztime2", "Mtime"} <= set(model.free)
    fl = prepare(fwid.load_flights(effect_flights("none", seed=0)[0])[0])
    t = np.asarray(fl.t)
    np.testing.assert_allclose(np.asarray(fl["time2"]), ((t - t[0]) / 10) ** 2, atol=1e-15)


def test_an_augmented_model_that_diverges_is_recorded_not_raised(effect_flights, monkeypatch):
    """A model with the effect in the EOM that blows up on a test flight (an outside user's
    yaw damping r|r| did): the diagnosis still comes back, the simulation block says why the
    simulated gap is not measured, and the summary says it."""
    from fwid import FitDivergedError
    from fwid.diagnosis import _simulation
    from fwid.report import diagnosis_summary, plot_gap_sim

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=4, n_test=4))
    real = _simulation.identify

    def identify(flights, model, **kw):
        if model.name != "lon":  # the augmented model
            raise FitDivergedError("lon_0.csv: the model's simulation of the flight is not "
                                   "finite")
        return real(flights, model, **kw)

    monkeypatch.setattr(_simulation, "identify", identify)
    d = fwid.diagnose(train, test, process_noise=False)
    sim = d.simulation
    assert d.verdict == "actuator-dynamics"
    assert sim["shrink_pct"] is None and sim["test_rms_after"] is None
    assert "not finite" in sim["message"] and not sim["converged_augmented"]
    assert sim["converged_baseline"] in (True, False) and d.models.augmented is None
    assert "in simulation: the model with actuator-dynamics in the EOM could not be" in (
        diagnosis_summary(d))
    # the written report (the CLI's path) survives it too: an outside stall case crashed here
    title = plot_gap_sim(d)._suptitle.get_text()
    assert "augmented model diverged" in title and "shrink" not in title



def test_the_augmented_fit_started_early_gives_the_same_block(effect_flights):
    """`EarlyFits` (the fits begun in a worker thread: the baseline's at once, the augmented
    model's when the selection's first round has its leader) and the fit made after the
    verdict give one simulation block, to the digit."""
    from fwid.diagnosis._simulation import EarlyFits

    train, test = (fwid.load_flights(p) for p in effect_flights(
        "actuator-dynamics", strength=1.0, seed=6, n_train=4, n_test=4))
    effects = [("actuator-dynamics", ("lag", 0.05))]
    early = EarlyFits(train, test, "lon", 5.0)
    early.start(effects)
    assert early.get([("actuator-dynamics", ("lag", 0.1))]) is None
    late = simulation_gap(train, test, "lon", effects, baseline=early.baseline.result())
    made_early = simulation_gap(train, test, "lon", effects, baseline=early.baseline.result(),
                                augmented=early.get(effects))
    early.close()
    assert made_early.augmented is not late.augmented
    assert made_early.summary["shrink_pct"] == late.summary["shrink_pct"] > 10.0
    assert made_early.summary["test_rms_after"] == late.summary["test_rms_after"]
    assert made_early.summary["warnings"] == late.summary["warnings"]


def test_a_diverging_simulation_gives_no_shrink():
    """A simulated state whose error is over ten times the measured signal's RMS has run away
    (an unstable identified model, open loop): such states are named, and `simulation_gap`
    then gives no shrink (a ratio of two huge numbers) but a message; a misfit is not named."""
    from fwid.diagnosis import _simulation

    ident = types.SimpleNamespace(validation=[types.SimpleNamespace(
        measured={"q": np.sin(np.arange(100.0))}, simulated={"q": 1e6 * np.ones(100)})])
    assert _simulation._diverged(ident, {"q": 1e6}) == ["q"]
    assert _simulation._diverged(ident, {"q": 0.5}) == []

    # the whole block: the augmented model's simulation runs away on the test flights
    from concurrent.futures import Future

    states = list(_simulation.get_model("lon").outputs)
    x = np.sin(np.arange(200.0) / 7.0)

    def identification(error):
        return types.SimpleNamespace(
            fits=[types.SimpleNamespace(converged=True, warnings=[])],
            validation=[types.SimpleNamespace(measured={s: x for s in states},
                                              simulated={s: x + error for s in states})])
    before, after = identification(0.1 * x), identification(1e6)
    augmented = Future()
    augmented.set_result((after, None, []))
    effects = [("nonlinear-aero", None)]
    block = _simulation.simulation_gap([], [], "lon", effects, baseline=before,
                                       augmented=augmented).summary
    assert block["shrink_pct"] is None
    assert block["diverged"] == sorted(states)
    assert "diverges" in block["message"]
    # the same block with a sane augmented simulation gives its shrink: 1 - 0.05 / 0.1
    augmented = Future()
    augmented.set_result((identification(0.05 * x), None, []))
    block = _simulation.simulation_gap([], [], "lon", effects, baseline=before,
                                       augmented=augmented).summary
    assert block["diverged"] == [] and "message" not in block
    assert abs(block["shrink_pct"] - 50.0) < 1e-9
