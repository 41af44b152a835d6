"""`fwid identify`: identify a model from flights, print a summary, and write `report.json`
and the figures to `--out` (the cycle-averaged models: Figures 6-11; the flapping and the
combined model: Figures 12-17)."""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

from .._errors import InputError
from ._inputs import (CONTROLS, IDENTIFY_COLUMNS, VEHICLE_MODELS, check_controls, check_paths,
                      read_sets, window_of)


def _stem(name: str) -> str:
    """A figure file stem for a flight: its name (a path below the inputs' common folder)
    without the suffix, folders joined by `__`, so equal file names in two folders differ."""
    return str(Path(name).with_suffix("")).replace("\\", "/").replace("/", "__")


def _json_option(path: str | None, flag: str, example: str):
    """The JSON object in the file of option `flag` (`None` without the option)."""
    if path is None:
        return None
    try:
        obj = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise InputError(f"{flag} {path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise InputError(f"{flag} {path}: not a readable JSON file ({e}); write {example}") from None
    if not isinstance(obj, dict):
        raise InputError(f"{flag} {path}: the file holds a {type(obj).__name__}, not an object; "
                         f"write {example}")
    return obj


def _fixed(items) -> dict[str, float]:
    """`--fix NAME=VALUE ...` as `{NAME: VALUE}` (a malformed one: an `InputError`)."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            if not (sep and name.strip()):
                raise ValueError
            out[name.strip()] = float(value)
        except ValueError:
            raise InputError(f"--fix {item}: not NAME=VALUE with a number for VALUE; write "
                             "e.g. --fix Xw=0") from None
    return out


def fixed_model(name: str, fixed: dict[str, float]):
    """The model `name` (`lon`, `lat`) with the parameters of `fixed` held at their values:
    `model.with_params(fixed).with_free(free minus fixed)`; a name that is not free: an
    `InputError` listing the free ones."""
    from fwid.identification._cycle_averaged import get_model

    model = get_model(name)
    if not fixed:
        return model
    unknown = [k for k in fixed if k not in model.free]
    if unknown:
        raise InputError(f"--fix {', '.join(unknown)}: not a free parameter of the {name} "
                         f"model; the free ones are {', '.join(model.free)}")
    return model.with_params(fixed).with_free([k for k in model.free if k not in fixed])


def identify(args) -> int:
    t0 = time.perf_counter()
    window = window_of(args)
    check_paths(args.data, args.validate)
    prior = _json_option(getattr(args, "prior", None), "--prior",
                         '{"Mq": {"mean": -0.001, "std": 0.0002}}')
    bounds = _json_option(getattr(args, "bounds", None), "--bounds",
                          '{"Mq": {"low": -0.01, "high": 0}}')
    if (prior is not None or bounds is not None) and args.model not in ("lon", "lat"):
        raise InputError(f"--prior and --bounds apply to --model lon or lat, not {args.model}; "
                         "drop them")
    method = getattr(args, "method", "output-error")
    if method != "output-error" and args.model not in ("lon", "lat"):
        raise InputError(f"--method {method} applies to --model lon or lat, not {args.model} "
                         "(fitted by regression); drop it")
    if (prior is not None or bounds is not None) and method != "output-error":
        raise InputError(f"--prior and --bounds work with --method output-error only, not "
                         f"--method {method}; drop them, or fit by output error")
    args.method = method
    args.prior_values, args.bounds_values = prior, bounds
    args.fixed = _fixed(getattr(args, "fix", None) or [])
    noise = getattr(args, "noise", None)
    for flag, given in (("--noise", noise is not None), ("--fix", bool(args.fixed))):
        if given and args.model not in ("lon", "lat"):
            raise InputError(f"{flag} applies to --model lon or lat, not {args.model}; drop it")
    args.noise = noise or "auto"
    vehicle = args.model if args.model in VEHICLE_MODELS else None
    require = [c for c in IDENTIFY_COLUMNS[args.model] if c != CONTROLS.get(args.model)]
    train, held_out = read_sets(args.data, args.validate, require=require, vehicle_for=vehicle,
                                window=window)
    check_controls(train, args.model)
    check_controls(held_out, args.model)
    import fwid  # JAX from here on: every file has been read and checked

    flights = fwid.data.build_flights(train)
    validate = fwid.data.build_flights(held_out)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        if args.model in ("flap", "combined"):
            report, figures, summary = _flapping(args, flights, validate)
        else:
            report, figures, summary = _cycle_averaged(args, flights, validate)
    report["warnings"] = _warnings_once(report, caught)
    if window is not None:  # seconds on each flight's own t; null: an open side
        report["window"] = list(window)
    print(summary(report))
    # the flights' own warnings (printed as they were read) lead the report's
    read = [w for r in (*train, *held_out) for w in r.warnings]
    report["warnings"] = list(dict.fromkeys([*read, *report["warnings"]]))
    if args.figures == "none":
        figures = []
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for draw in figures:  # drawn once the report is known to be complete
            draw(out)
        fwid.write_json(out / "report.json", report)
        fwid.report.write_text(out / "parameters.csv",
                               fwid.report.parameters_csv(report["parameters"]))
        print(f"\nfwid: report and figures in {out}/ ({time.perf_counter() - t0:.1f} s)")
    else:
        print("\nfwid: nothing written (give --out DIR for report.json and the figures)")
    return _exit_code(report)


def _warnings_once(report: dict, caught) -> list[str]:
    """Every warning of the run once, in order: the report's own (the fits'), then those
    the run issued besides (missing force columns, a closed loop, ...). Warnings of other
    kinds (a library's) are printed as one line each and left out of the report."""
    found = list(report.get("warnings") or [])
    for w in caught:
        if issubclass(w.category, UserWarning):
            found.append(str(w.message))
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return list(dict.fromkeys(found))


def _exit_code(report: dict) -> int:
    """1, with one line on stderr naming the flights and why, when no fit converged;
    else 0."""
    from fwid.report import converged_flags, failure_reason

    flags = converged_flags(report)
    if flags and not any(flags):
        print(f"fwid: error: no fit converged (flights: {', '.join(report['flights'])}): "
              f"{failure_reason(report)}", file=sys.stderr)
        return 1
    return 0


def _cycle_averaged(args, flights, validate):
    """`--model lon|lat`: Section IV; with `--joint --validate`, joint vs individual."""
    import fwid
    from fwid.report import (identification_summary, joint_report, joint_summary,
                             plot_fits_overview, spread_table)

    model = fixed_model(args.model, args.fixed)
    ident = fwid.identify(flights, model, validate=validate, joint=args.joint,
                          cutoff=args.cutoff, progress=not args.quiet,
                          prior=args.prior_values, bounds=args.bounds_values,
                          method=args.method, noise=args.noise)
    report = {**fwid.identification_report(ident), "method": args.method}
    parts = []
    comparison = None
    if args.joint and validate and len(flights) > 1:  # does sharing pay off?
        comparison = fwid.compare_joint(flights, model, validate=validate, joint=ident,
                                        cutoff=args.cutoff, progress=not args.quiet,
                                        prior=args.prior_values, bounds=args.bounds_values,
                                        method=args.method, noise=args.noise)
        report["joint_vs_individual"] = joint_report(comparison)
        spread = report["joint_vs_individual"]["modes"]["individual_spread"]
        parts += ["\n" + joint_summary(comparison),
                  "\n" + spread_table(spread, f"mode spread over the {spread['flights']} "
                                             "training flights, each fitted alone (the joint "
                                             "model's modes are above):")]

    def figures(out):
        fits = [*ident.estimation, *ident.validation]
        plot_fits_overview(fits, path=out / "fits.png", title=f"{args.model} model",
                           parts=["estimation"] * len(ident.estimation)
                           + ["validation"] * len(ident.validation))
        for ff in ident.estimation if args.figures == "all" else ():
            fwid.plot_flight_fit(ff, path=out / f"fit_{_stem(ff.name)}.png",
                                 title=f"{ff.name}: estimation ({args.model})")
        for ff in ident.validation if args.figures == "all" else ():
            fwid.plot_flight_fit(ff, path=out / f"validation_{_stem(ff.name)}.png",
                                 title=f"{ff.name}: validation ({args.model})")
        eigs = [fwid.eigenvalues(f.model, ident.consts) for f in ident.fits]
        labels = (list(ident.flights) if len(ident.fits) > 1
                  else ["joint" if args.joint else ident.flights[0]])
        if comparison is not None:  # the joint model beside every individual fit
            ind = comparison.individual
            eigs += [fwid.eigenvalues(f.model, ind.consts) for f in ind.fits]
            labels += [f"{n} (alone)" for n in ind.flights]
        fwid.plot_poles(eigs, labels, path=out / "poles.png",
                        highlight=0 if args.joint else None,
                        title=f"{args.model} model eigenvalues")

    def summary(report):
        return "\n".join([identification_summary(report), *parts])

    return report, [figures], summary


def _flapping(args, flights, validate):
    """`--model flap|combined`: Sections V-VI (Figures 12-17)."""
    import fwid
    from fwid.report import combined_report, flapping_report, flapping_summary

    progress = not args.quiet
    figures = []

    def time_and_spectrum(ff, f, path, title, **kw):
        figures.append(lambda out: fwid.plot_time_and_spectrum(
            ff, f=f, path=out / path, title=title, **kw))

    if args.model == "flap":
        ident = fwid.identify_flapping_model(flights, validate=validate, joint=args.joint,
                                             cutoff=args.cutoff, progress=progress)
        steady = []
        for f in flights:
            try:
                steady.append(fwid.steady_vs_manoeuvre(f, ident.model.outputs, cutoff=args.cutoff))
            except fwid.InputError as e:
                if progress:
                    print(f"fwid: steady vs manoeuvre skipped: {e}", flush=True)
        report = flapping_report(ident, steady)
        for ff in ident.estimation:
            time_and_spectrum(ff, ident.frequencies[ff.name], f"flap_fit_{_stem(ff.name)}.png",
                              f"{ff.name}: flapping forces, estimation (Figure 12)")
        for ff in ident.validation:
            time_and_spectrum(ff, ident.frequencies[ff.name],
                              f"flap_validation_{_stem(ff.name)}.png",
                              f"{ff.name}: flapping forces, validation, phase aligned (Figure 13)")
        for s in steady:
            figures.append(lambda out, s=s: fwid.plot_steady_vs_manoeuvre(
                s.steady, s.manoeuvre, f=s.frequency,
                path=out / f"steady_vs_manoeuvre_{_stem(s.flight)}.png",
                title=f"{s.flight}: flapping model, steady flight vs manoeuvre (Figure 14)"))
    else:
        ident = fwid.identify_combined(flights, validate=validate, joint=args.joint,
                                       cutoff=args.cutoff, progress=progress)
        report = combined_report(ident)
        model_labels = dict(measured_label="Measured", model_label="Model")
        for ff in ident.flapping.estimation:
            time_and_spectrum(ff, ident.frequencies[ff.name], f"flap_fit_{_stem(ff.name)}.png",
                              f"{ff.name}: flapping forces, estimation (Figure 12)")
        for ff in ident.estimation:
            p = ident.parts[ff.name]
            figures.append(lambda out, ff=ff, p=p: fwid.plot_superposition(
                ff.t, ff.forces_measured, p["TA"], p["TV"], f=ident.frequencies[ff.name],
                path=out / f"superposition_{_stem(ff.name)}.png",
                title=f"{ff.name}: time-averaged + time-varying model (Figure 15)"))
            time_and_spectrum(ff, ident.frequencies[ff.name],
                              f"combined_fit_{_stem(ff.name)}.png",
                              f"{ff.name}: combined model, estimation (Figure 16)", **model_labels)
        for ff in ident.validation:
            time_and_spectrum(ff, ident.frequencies[ff.name],
                              f"combined_validation_{_stem(ff.name)}.png",
                              f"{ff.name}: combined model, validation (Figure 17)", **model_labels)
        figures.append(lambda out: fwid.plot_poles(
            [ident.eigenvalues], ["cycle-averaged part"], path=out / "poles.png",
            title="combined model: eigenvalues of the cycle-averaged part"))
    return report, figures, flapping_summary
