"""`fwid simulate`: write simulated DelFly-like flights (the embedded default data)."""

from __future__ import annotations


def simulate(args) -> int:
    from ..synth import write_flights

    paths = write_flights(args.out_dir, n_flights=args.flights, axis=args.axis, seed=args.seed,
                          effect=args.effect, strength=args.strength, duration=args.duration,
                          drift=args.drift, prefix=args.prefix)
    names = f"{paths[0].name} .. {paths[-1].name}" if paths else "none"
    print(f"fwid: wrote {len(paths)} {args.axis} flights to {args.out_dir} ({names})")
    return 0
