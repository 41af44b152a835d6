"""The least-squares engine of the attribution against an independent computation."""

from __future__ import annotations

import numpy as np

from fwid.diagnosis._regression import Projector, local_design, normal_equations, solve


def _units(rng, k=3, n=400, cols=4):
    out = []
    theta = rng.normal(size=cols)
    for _ in range(k):
        g = rng.normal(size=(n, cols))
        g[:, -1] = 0.0  # a column that never moves (rank deficiency)
        phase = np.cumsum(np.full(n, 0.3))
        y = g @ theta + 2.0 + np.sin(phase) + 0.1 * rng.normal(size=n)
        out.append((g, y, Projector(local_design(phase))))
    return out


def test_solve_matches_lstsq_on_the_stacked_projected_design():
    rng = np.random.default_rng(0)
    units = _units(rng)
    theta, sse = solve([normal_equations(g, y, p) for g, y, p in units])
    a = np.concatenate([p(g) for g, y, p in units])
    b = np.concatenate([p(y) for g, y, p in units])
    ref, *_ = np.linalg.lstsq(a, b, rcond=None)  # minimum norm: the dead column gets 0
    assert np.allclose(theta, ref, rtol=1e-9, atol=1e-12)
    assert theta[-1] == 0.0
    assert np.isclose(sse, np.sum((b - a @ ref) ** 2), rtol=1e-9)


def test_solve_sums_units():
    """A fit on any set of units is the sum of their normal equations (the cross-fit's folds
    reuse them)."""
    rng = np.random.default_rng(1)
    units = _units(rng, k=4)
    parts = [normal_equations(g, y, p) for g, y, p in units]
    for idx in ((0, 1), (1, 2, 3), (0, 3)):
        a = np.concatenate([units[i][2](units[i][0]) for i in idx])
        b = np.concatenate([units[i][2](units[i][1]) for i in idx])
        ref, *_ = np.linalg.lstsq(a, b, rcond=None)
        assert np.allclose(solve([parts[i] for i in idx])[0], ref, rtol=1e-9, atol=1e-12)


def test_solve_stack_solves_each_member_as_lstsq_does():
    """Leave-one-unit-out fits solved as one stack equal `np.linalg.lstsq` on each member,
    also where a column is dead in one member only (solved one by one) and where the
    Gram matrix is singular (a repeated column: the minimum-norm solution)."""
    from fwid.diagnosis._regression import solve_stack

    rng = np.random.default_rng(3)
    designs = [rng.normal(size=(200, 4)) for _ in range(4)]
    designs[1][:, 2] = designs[1][:, 0]  # singular in that member
    designs[3][:, 1] = 0.0  # a column dead in one member only
    ys = [rng.normal(size=200) for _ in designs]
    for stack in (designs[:3], designs):
        ata = np.stack([g.T @ g for g in stack])
        atb = np.stack([g.T @ y for g, y in zip(stack, ys)])
        theta = solve_stack(ata, atb)
        for g, y, th in zip(stack, ys, theta):
            ref, *_ = np.linalg.lstsq(g, y, rcond=None)
            assert np.allclose(th, ref, rtol=1e-8, atol=1e-10)
