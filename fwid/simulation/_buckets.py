"""Padded lengths: flights padded to one of a few lengths, so that a flight of a new length
reuses a compiled program instead of compiling its own.

XLA compiles a program per array shape. [`bucket_length`][] rounds a length up to one of
eight lengths per octave (`m 2^k` for `m = 8 .. 15`, at least 64): at most 12.5 % more
samples, and every flight from 897 to 960 samples (4.48-4.8 s at 200 Hz) shares one program.
The padding is masked (`Experiment.mask`), so no padded sample enters a cost, a fit or a
metric: the results equal those on the unpadded flights (to rounding).
"""

from __future__ import annotations

import equinox as eqx

from ._experiment import Experiment, stack_experiments

#: The shortest padded length.
MIN_BUCKET = 64


def bucket_length(n: int) -> int:
    """The padded length for `n` samples: the smallest `m 2^k >= n` with `8 <= m < 16`
    (at least `MIN_BUCKET`)."""
    n = int(n)
    if n <= MIN_BUCKET:
        return MIN_BUCKET
    step = 1 << (n.bit_length() - 4)  # 2^k with 8 2^k <= n < 16 2^k
    return -(-n // step) * step


def pad_experiment(exp: Experiment, n: int | None = None) -> Experiment:
    """`exp` padded to `n` samples (default: its [`bucket_length`][]) as
    [`fwid.stack_experiments`][] pads: time continues on the grid, inputs, outputs and
    forces hold their last value, the mask is 0 on the padding. Unchanged if already that
    long."""
    n = bucket_length(exp.n) if n is None else n
    if n == exp.n:
        return exp
    b = stack_experiments([exp], n)
    fields = [lambda e: e.t, lambda e: e.u, lambda e: e.z, lambda e: e.mask]
    values = [b.t[0], b.u[0], b.z[0], b.mask[0]]
    if exp.forces is not None:
        fields.append(lambda e: e.forces)
        values.append(b.forces[0])
    return eqx.tree_at(lambda e: tuple(f(e) for f in fields), exp, tuple(values))
