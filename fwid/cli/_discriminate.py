"""`fwid design --discriminate DIAGNOSIS_DIR`: the input that tells the diagnosis's two closest
effects apart.

`diagnosis.json` names the effects and their variants (time constants, ...) but holds neither
the flights' paths (only their names) nor the fitted parameters of the runner-up's augmented
model (the `simulation` block fits the verdict's alone). So both augmented models are fitted
again here, jointly on the training flights, as the diagnosis's simulation block fits the
verdict's (`fwid.diagnosis._simulation`): the flights come from `--train`, or from the
`method.train_paths` that `fwid diagnose --out` now records. `unsteady-aero`'s lagging part
of the states, a prepared input in the fit, is made from the model's own simulated states in
the prediction (`fwid.diagnosis._lag_states`), so the designed control drives it. The extra
inputs it cannot drive (the other axis's states, the flapping frequency, the time) are held
at zero: effects acting only through them are not told apart by this input, and the output
says so. By default (`--discriminate-by loads`) the design compares the two models' predicted
loads along either model's trajectory (`load_maps`), as the diagnosis compares the effects on
the loads of the flown flight; `--discriminate-by outputs` compares their predicted states.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from .._errors import InputError


def _variant(text, axis: str = "lon"):
    """The variant back from `diagnosis.json`'s text (`_scores.variant_text`)."""
    if text is None:
        return None
    if text == "at once":
        return 0.0
    if text.startswith(("terms ", "smooth ", "products ")):
        return None  # a smooth member needs its numbers (`member`): the baseline stands for it
    from ..diagnosis._catalogue import ACTUATOR_FILTERS, filter_text

    for v in ACTUATOR_FILTERS:  # the members of actuator-dynamics' family in words
        if v[0] not in ("lag", "delay") and filter_text(v) == text:
            return v
    m = re.fullmatch(r"first-order lag, tau = ([-+0-9.eE]+) s", text)
    if m:
        return ("lag", float(m.group(1)))
    m = re.fullmatch(r"delay ([-+0-9.eE]+) s", text)
    if m:
        return ("delay", float(m.group(1)))
    m = re.fullmatch(r"([-+0-9.eE]+) s", text)
    if m:
        return float(m.group(1))
    raise InputError(f"diagnosis.json: cannot read the variant {text!r}")


def close_pair(diag: dict) -> list[tuple[str, object]]:
    """The two effects the diagnosis left closest: the first effects of the first two
    explanations of the confidence set that start with different catalogue entries (the
    flights cannot tell them apart); for a report without a set, the first effect with a
    near-tie runner-up, else the first effect and its runner-up; else the two best-ranked
    candidates."""
    from ..diagnosis._catalogue import member_from_json
    from ..diagnosis._confidence import rivals

    variants = {c["effect"]: c.get("variant") for c in diag.get("candidates", [])}
    members = {c["effect"]: c["member"] for c in diag.get("candidates", []) if "member" in c}
    axis = diag.get("axis", "lon")

    def member(n):  # every number of the member when the report has them, else its words
        if n in members:
            try:
                return member_from_json(n, members[n])
            except (ValueError, KeyError, TypeError) as exc:
                raise InputError(f"diagnosis.json: cannot read {n}'s member ({exc})") from None
        return _variant(variants.get(n), axis)

    firsts = rivals(diag.get("confidence_set") or [], list(variants))
    if len(firsts) >= 2:
        return [(n, member(n)) for n in firsts[:2]]
    rows = diag.get("effects") or []
    pick = next((r for r in rows if r.get("near_tie")), rows[0] if rows else None)
    if pick is not None and pick.get("runner_up"):
        names = [pick["effect"], pick["runner_up"]["effect"]]
    else:
        names = [c["effect"] for c in diag.get("candidates", [])][:2]
    if len(names) < 2:
        raise InputError("diagnosis.json: no two candidate effects to tell apart")
    return [(n, member(n)) for n in names]


def control_map(model, axis: str, variant_of_control):
    """`(t, u) -> model inputs`: the control (through the diagnosed actuator filter when the
    model's first input is the acting deflection), the other inputs at zero."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from ..diagnosis._lag_states import jax_lag as lag

    nu = len(model.inputs)
    shift = variant_of_control

    def stepped(u, dt, p, kind):
        """The rate-limited or direction-dependent lag (`_catalogue.actuator_filter`)."""
        xm = 0.5 * (u + jnp.concatenate([u[:1], u[:-1]]))
        if kind == "rate-limit":
            k, lim = 1.0 - jnp.exp(-dt / p[0]), p[1] * dt

            def step(y, x):
                y = y + jnp.clip(k * (x - y), -lim, lim)
                return y, y
        else:
            ku, kd = 1.0 - jnp.exp(-dt / p[0]), 1.0 - jnp.exp(-dt / p[1])

            def step(y, x):
                y = y + jnp.where(x > y, ku, kd) * (x - y)
                return y, y
        _, ys = jax.lax.scan(step, u[0], xm)
        return ys

    def second_order(u, dt, fn, zeta):
        from scipy.signal import bilinear, lfilter_zi

        wn = 2 * np.pi * fn
        b, a = bilinear([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn], fs=1.0 / dt)
        zi = lfilter_zi(b, a)

        def step(z, x):  # transposed direct form II, as scipy's lfilter
            y = b[0] * x + z[0]
            z = jnp.stack([b[1] * x + z[1] - a[1] * y, b[2] * x - a[2] * y])
            return z, y
        _, ys = jax.lax.scan(step, jnp.asarray(zi) * u[0], u)
        return ys

    def play(u, size):
        """The backlash of `_filters.backlash`, traced."""
        def step(y, x):
            y = jnp.where(x > y + size / 2, x - size / 2, jnp.where(x < y - size / 2,
                                                                   x + size / 2, y))
            return y, y
        _, ys = jax.lax.scan(step, u[0], u)
        return ys

    def static(u, kind, size):
        """The servo's static nonlinearity, in JAX."""
        from ..diagnosis._catalogue.actuator_dynamics import static as servo

        return servo(u, kind, size, xp=jnp, play=play)

    def inputs(t, u):
        x = u
        if shift is not None:
            kind, *p = shift
            dt = float(t[1] - t[0])
            tt = jnp.asarray(t)
            if kind == "delay":
                x = jnp.interp(tt - p[0], tt, u)
            elif kind == "lag":
                x = lag(u, dt, p[0])
            elif kind == "lag-delay":
                x = lag(jnp.interp(tt - p[1], tt, u), dt, p[0])
            elif kind == "second-order":
                x = second_order(u, dt, *p)
            elif kind in ("saturation", "dead-band", "backlash"):
                tau, size, order = p
                x = lag(static(u, kind, size), dt, tau) if order == "before" else static(
                    lag(u, dt, tau), kind, size)
            else:
                x = stepped(u, dt, p, kind)
        return jnp.zeros((u.shape[0], nu)).at[:, 0].set(x)
    return inputs


def discriminating_models(axis: str, pair, flights, say=None):
    """The two augmented models of `pair` (`(effect, variant)`), each fitted jointly on
    `flights` from the baseline's joint fit (`unsteady-aero`'s with its lags as states,
    `lag_states`); their control maps; what is held at zero; the constants and the
    baseline's R."""
    import warnings

    import numpy as np

    from fwid.diagnosis._augment import augment
    from fwid.diagnosis._lag_states import lag_states
    from fwid.identification import identify

    if say:
        say(f"re-fitting the models with {pair[0][0]} and with {pair[1][0]} on "
            f"{len(flights)} training flights")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = identify(flights, axis, joint=True)
        fitted = {k: float(v) for k, v in base.model.params.items() if k not in base.model.local}
        models, maps, held = [], [], []
        for name, variant in pair:
            model, prepare, left_out = augment(axis, [(name, variant)])
            if left_out:
                models.append(base.model)
                maps.append(control_map(base.model, axis, None))
                held.append(f"{name} has no form inside the cycle-averaged EOM: the baseline "
                            "stands for it")
                continue
            ident = identify([prepare(f) for f in flights], model.with_params(fitted),
                             joint=True, start="model")
            m = ident.model.with_params({k: 0.0 for k in ident.model.local})
            if name == "unsteady-aero":  # the lagging part from the simulated states
                try:
                    m = lag_states(m, axis, variant)
                except (ValueError, AttributeError) as exc:
                    raise InputError(f"unsteady-aero: {exc}") from None
            models.append(m)
            shift = variant if name == "actuator-dynamics" else (
                ("delay", -float(variant)) if name == "time-offset" else None)
            maps.append(control_map(m, axis, shift))
            extra = list(m.inputs[1:])
            if extra:
                held.append(f"{name}: inputs {', '.join(extra)} held at zero (not driven by "
                            "the control)")
    base_model = base.model.with_params({k: 0.0 for k in base.model.local})
    models = [base_model if m is base.model else m for m in models]
    consts = {k: float(np.asarray(v)) for k, v in base.consts.items()
              if k in base.model.constants}
    return models, maps, held, consts, np.asarray(base.fit.R)


def load_maps(models, maps, consts):
    """Each model's `(t, u, y) -> (n, loads)`: its force model (Eqs. 1-6 with the effect's
    terms) along the trajectory `y` of its outputs for the control `u` (through its control
    map), the lag states of `unsteady-aero`'s model made from `y` as the diagnosis makes
    the lag inputs from the measured states (`fwid.diagnosis._lag_states.states_along`)."""
    import jax
    import jax.numpy as jnp

    from fwid.diagnosis._lag_states import states_along

    c = {k: jnp.asarray(v, dtype=float) for k, v in consts.items()}

    def one(model, inputs):
        def loads(t, u, y):
            x = states_along(model, y, float(t[1] - t[0]))
            return jax.vmap(lambda xk, uk: model.forces(xk, uk, model.params, c))(
                x, inputs(t, u))
        return loads
    return [one(m, mp) for m, mp in zip(models, maps)]


#: The design of `fwid diagnose --out`'s next flight: `fwid design`'s defaults but for the
#: optimisation's grid (50 Hz) and restarts (3), those the discrimination benchmark
#: (`benchmarks/design.py --part discrimination`) measures, so that an ambiguous diagnosis is
#: not many times slower than a decisive one (`fwid design --discriminate` takes more); the
#: amplitude that of the flights flown (`flown_amplitude`).
NEXT_FLIGHT = {"duration": 5.0, "quiet": 1.0, "parametrisation": "steps", "switch_rate": 10.0,
               "rate": 50.0, "attitude_limit": None, "restarts": 3, "seed": 0,
               "by": "loads"}
#: The control of each axis.
CONTROL = {"lon": "de", "lat": "dr"}


def flown_amplitude(flights, axis: str) -> float:
    """The amplitude of the manoeuvres flown: the median over `flights` of half the
    peak-to-peak of the axis's control (rad). The designed flight is then of the same kind
    as those the diagnosis saw, as its models were fitted on them."""
    import numpy as np

    c = CONTROL[axis]
    return float(np.median([0.5 * float(np.ptp(np.asarray(f[c]))) for f in flights]))


def design_for(diag: dict, flights, settings: dict, say=None):
    """The discriminating input of the diagnosis `diag` (`diagnosis.json`) designed on both
    fitted models (`discriminating_models` on `flights`) with `settings` (the keys of
    `NEXT_FLIGHT` and `amplitude`): the `Discrimination`, the record of the pair for
    `design.json` and the pair."""
    import fwid

    axis = diag.get("axis", "lon")
    pair = close_pair(diag)
    models, maps, held, consts, R = discriminating_models(axis, pair, flights, say)
    by = settings["by"]
    loads = load_maps(models, maps, consts) if by == "loads" else (None, None)
    limit = settings["attitude_limit"]
    d = fwid.design_discriminating(
        models[0], models[1], consts=consts, R=R, amplitude=settings["amplitude"],
        duration=settings["duration"], quiet=settings["quiet"], inputs_a=maps[0],
        inputs_b=maps[1], parametrisation=settings["parametrisation"],
        switch_rate=settings["switch_rate"], rate=settings["rate"],
        attitude={"lon": "theta", "lat": "phi"}[axis],
        attitude_bound="3211" if limit is None else 0.8 * limit,
        restarts=settings["restarts"], seed=settings["seed"], progress=say or False,
        loads_a=loads[0], loads_b=loads[1])
    info = {"pair": [{"effect": n, "variant": None if v is None else v} for n, v in pair],
            "refit_on": [f.name for f in flights], "held": held, "compared": by,
            **({"S": "each load's standard deviation along model a's prediction of the "
                     "reference 3211"} if by == "loads" else
               {"R": "the baseline's joint fit (Eq. 11)"})}
    return d, info, pair


def next_flight_input(diag: dict, flights, out: Path, say=None, **settings) -> dict:
    """`fwid diagnose --out`'s discriminating input for an ambiguous set: designed on both
    fitted models (`design_for`, `NEXT_FLIGHT` at the `flown_amplitude` of the training
    `flights`), written to `out/next_flight.csv` (the format of `fwid design`'s
    `input.csv`); returns what `diagnosis.json`'s `next_flight` gains: the file, the
    settings (`fwid design --discriminate` without `--amplitude` takes them), the
    criterion and the limits; `{"failed": reason}` when the design failed (the diagnosis
    stands). `settings`: any of `NEXT_FLIGHT`'s, changed."""
    from fwid._errors import FwidError
    from fwid.diagnosis._diagnose import failed_block
    from fwid.report._design import discrimination_csv
    from fwid.report._json import write_text

    axis = diag.get("axis", "lon")
    settings = {**NEXT_FLIGHT, "amplitude": flown_amplitude(flights, axis), **settings}
    try:
        d, info, _ = design_for(diag, flights, settings, say)
    except (FwidError, ArithmeticError, ValueError) as exc:
        return failed_block(exc, "next-flight design")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "next_flight.csv", discrimination_csv(d, CONTROL[axis]))
    return {"input": "next_flight.csv", "control": CONTROL[axis], "samples": int(d.t.size),
            "design": settings, "held": info["held"], "compared": info["compared"],
            "criterion": d.to_json()["criterion"], "chosen": d.settings["chosen"],
            "limits": d.limits}


def discriminate(args) -> int:
    from fwid.design._design import check_limits

    path = Path(args.discriminate) / "diagnosis.json"
    if not path.is_file():
        raise InputError(f"{path}: no such file; give the folder `fwid diagnose --out DIR` "
                         "wrote")
    try:
        diag = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not JSON ({exc})") from None
    axis = diag.get("axis")
    if args.model is not None and args.model != axis:
        raise InputError(f"{path}: the diagnosis is of the {axis!r} axis, not {args.model!r}")
    settings = {"duration": args.duration, "quiet": args.quiet, "amplitude": args.amplitude,
                "parametrisation": args.parametrisation, "switch_rate": args.switch_rate,
                "rate": args.rate, "attitude_limit": args.attitude_limit,
                "restarts": args.restarts, "seed": args.seed, "by": args.discriminate_by}
    if args.amplitude is None:  # the next flight the diagnosis designed, again
        nxt = diag.get("next_flight") or {}
        recorded = nxt.get("design")
        if recorded is None:
            why = f" (its design failed: {nxt['failed']})" if nxt.get("failed") else ""
            raise InputError(f"{path}: the diagnosis designed no next flight to take the "
                             f"settings from{why}; give --amplitude (peak deflection [rad])")
        settings = {**settings, **recorded}
    check_limits(settings["duration"], settings["amplitude"], settings["quiet"],
                 settings["rate"], settings["switch_rate"])
    train = args.train or diag.get("method", {}).get("train_paths")
    if not train:
        raise InputError(f"{path}: the diagnosis names its training flights "
                         f"({', '.join(diag.get('train', []))}) but not where they are; give "
                         "them with --train DATA...")
    from ._inputs import DIAGNOSE_COLUMNS, check_paths, read_sets

    check_paths(train)
    window = diag.get("method", {}).get("window")  # the diagnosis's --window, if any
    (records,) = read_sets(train, require=DIAGNOSE_COLUMNS[axis][:5], vehicle_for=axis,
                           window=None if window is None else tuple(window))
    import fwid
    from fwid.report._design import write_discrimination

    flights = fwid.data.build_flights(records)
    say = (lambda m: print(f"fwid: {m}", file=sys.stderr)) if not args.quiet_progress else None
    d, info, pair = design_for(diag, flights, settings, say)
    control = CONTROL[axis]
    written = write_discrimination(d, control, info, Path(args.out))
    ratio = d.to_json()["criterion"]["ratio"]
    print(f"fwid: input telling {pair[0][0]} from {pair[1][0]}: expected difference "
          f"{d.distance:.3g} (" + (f"{ratio:.2f}x a 3211's)" if ratio is not None else
                                   "a model's prediction of a 3211 diverges)"))
    used = d.limits["amplitude_used_rad"]
    if used < settings["amplitude"]:
        print(f"fwid: amplitude lowered to {used:.3g} rad: a model's prediction of a 3211 of "
              f"{2 * used:.3g} rad diverges (a model fitted on smaller manoeuvres)")
    print(f"fwid: {', '.join(written)} in {args.out}/")
    return 0
