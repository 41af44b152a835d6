"""`fwid simulate`: write simulated DelFly-like flights (the embedded default data)."""

from __future__ import annotations


def simulate(args) -> int:
    from .._errors import InputError
    from ..synth import ALIASES, FORMS, write_flights

    args.effect = ALIASES.get(args.effect, args.effect)
    if args.form is not None and args.form not in FORMS.get(args.effect, ()):
        raise InputError(f"--form {args.form!r} is not a form of --effect {args.effect}: choose "
                         f"one of {', '.join(FORMS.get(args.effect, ()))}")
    paths = write_flights(args.out_dir, n_flights=args.flights, axis=args.axis, seed=args.seed,
                          effect=args.effect, strength=args.strength, duration=args.duration,
                          drift=args.drift, prefix=args.prefix, form=args.form)
    names = f"{paths[0].name} .. {paths[-1].name}" if paths else "none"
    print(f"fwid: wrote {len(paths)} {args.axis} flights to {args.out_dir} ({names})")
    return 0
