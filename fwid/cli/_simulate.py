"""`fwid simulate`: write simulated DelFly-like flights (the embedded default data), or with
`--raw` the raw recordings of 6-DOF flights (the raw-recording formats)."""

from __future__ import annotations

#: `--raw` options: (argument, keyword of `write_raw_flights`, scale to its unit, lower bound).
_RAW_OPTIONS = (("rate", "rate", 1.0, 0.0), ("position_noise", "position_noise", 1e-3, None),
                ("attitude_noise", "attitude_noise", 1.0, None), ("dropouts", "dropouts", 1.0, None),
                ("onboard_rate", "onboard_rate", 1.0, 0.0), ("clock_offset", "clock_offset", 1.0, None))


def _raw_options(args) -> dict:
    from .._errors import InputError

    kw = {}
    for name, key, scale, _ in _RAW_OPTIONS:
        value = getattr(args, name, None)
        if value is None:
            continue
        flag = "--" + name.replace("_", "-")
        if args.raw is None:
            raise InputError(f"{flag} applies to raw recordings only: add --raw fwid or --raw motive")
        if value != value or abs(value) == float("inf"):
            raise InputError(f"{flag} must be a finite number, got {value}")
        if name in ("rate", "onboard_rate") and not 50.0 <= value <= 2000.0:
            raise InputError(f"{flag} {value:g} Hz is outside 50-2000 Hz: give a tracking/log rate in that range")
        if name in ("position_noise", "attitude_noise") and value < 0:
            raise InputError(f"{flag} must be >= 0, got {value:g}")
        if name == "dropouts" and not 0.0 <= value < 0.2:
            raise InputError(f"--dropouts is a share of frames in [0, 0.2), got {value:g}")
        kw[key] = value * scale
    return kw


def simulate(args) -> int:
    from .._errors import InputError
    from ..synth import ALIASES, FORMS, write_flights

    args.effect = ALIASES.get(args.effect, args.effect)
    if args.form is not None and args.form not in FORMS.get(args.effect, ()):
        raise InputError(f"--form {args.form!r} is not a form of --effect {args.effect}: choose "
                         f"one of {', '.join(FORMS.get(args.effect, ()))}")
    common = dict(n_flights=args.flights, axis=args.axis, seed=args.seed, effect=args.effect,
                  strength=args.strength, duration=args.duration, drift=args.drift,
                  prefix=args.prefix, form=args.form)
    raw = _raw_options(args)
    if args.raw is not None:
        from ..synth import write_raw_flights

        paths = write_raw_flights(args.out_dir, raw=args.raw, **common, **raw)
        what = f"{args.axis} raw takes ({args.raw} form, 6-DOF; truth in truth/)"
    else:
        paths = write_flights(args.out_dir, **common)
        what = f"{args.axis} flights"
    names = f"{paths[0].name} .. {paths[-1].name}" if paths else "none"
    print(f"fwid: wrote {len(paths)} {what} to {args.out_dir} ({names})")
    return 0
