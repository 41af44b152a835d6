"""The `fwid` command line's arguments (CONTRACTS section 2)."""

from __future__ import annotations

import argparse


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="fwid",
        description="Identify flapping-wing vehicle dynamics from flight data (Armanini et al.).",
    )
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("simulate", help="write simulated DelFly-like flights (the default data)")
    s.add_argument("out_dir")
    s.add_argument("--flights", type=int, default=4)
    s.add_argument("--axis", choices=("lon", "lat"), default="lon")
    s.add_argument("--effect", default="none")
    s.add_argument("--strength", type=float, default=1.0)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--duration", type=float, default=4.5, help="seconds per flight")
    s.add_argument("--drift", action="store_true", help="drifting flapping frequency")

    i = sub.add_parser("identify", help="identify a model from flights")
    i.add_argument("data", nargs="+", help="CSV files or folders of them")
    i.add_argument("--model", choices=("lon", "lat", "flap", "combined"), required=True)
    i.add_argument("--joint", action="store_true",
                   help="one parameter set for all flights (each keeps its own biases); with "
                   "--validate, each flight is also fitted alone and the report says which "
                   "validates better on the held-out flights (joint_vs_individual)")
    i.add_argument("--validate", nargs="+", default=[], metavar="DATA")
    i.add_argument("--out", default=None, help="folder for report.json and the figures")
    i.add_argument("--cutoff", type=float, default=5.0, help="cycle-averaged / flapping split [Hz]")
    i.add_argument("--quiet", action="store_true")

    d = sub.add_parser("diagnose", help="where the model misses, which effect explains it, "
                                        "how far the held-out error shrinks once it is added")
    d.add_argument("--train", nargs="+", required=True, metavar="DATA")
    d.add_argument("--test", nargs="+", required=True, metavar="DATA")
    d.add_argument("--axis", choices=("lon", "lat"), default="lon")
    d.add_argument("--out", default=None, help="folder for diagnosis.json and the figure")
    d.add_argument("--quiet", action="store_true")
    return p
