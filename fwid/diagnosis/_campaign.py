"""The flights of one diagnosis, prepared once and passed through its stages: their signals
(Section III.B's split), the scoring blocks, the least-squares engine, the cross-fit's folds,
and the catalogue's families made for the training flights."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

from ..data import Flight
from ._attribution import Engine, units
from ._catalogue import Effect
from ._significance import Half, cross_fit_folds, scoring_blocks
from ._signals import AXIS_LOADS, LOADS, Signals, check_axis, check_excitation, signals


@dataclasses.dataclass
class Campaign:
    """`train`, `test` (flights) and their `signals` (`tr_sig`, `te_sig`); `loads` (those every
    flight has, the manoeuvred axis's first); `engine` over the flights then their scoring
    blocks (`train_idx`, `test_idx`, `block_idx` its units); `sigma2` (the baseline's training
    mean square per channel); `halves` (the cross-fit's folds); `catalogue` (bound to the
    training flights, `Effect.bound`) and `probes`."""

    train: list[Flight]
    test: list[Flight]
    axis: str
    cutoff: float
    loads: tuple[str, ...]
    tr_sig: list[Signals]
    te_sig: list[Signals]
    engine: Engine
    train_idx: tuple[int, ...]
    test_idx: tuple[int, ...]
    block_idx: tuple[int, ...]
    sigma2: dict
    halves: list[Half]
    catalogue: tuple[Effect, ...]
    probes: tuple[Effect, ...]

    @property
    def candidates(self) -> tuple[Effect, ...]:
        return self.catalogue + self.probes

    @property
    def own(self) -> list[str]:
        """The manoeuvred axis's loads."""
        return [ld for ld in self.loads if ld in AXIS_LOADS[self.axis]]


def campaign(train: Sequence[Flight], test: Sequence[Flight], axis: str, cutoff: float,
             catalogue: Sequence[Effect], probes: Sequence[Effect], folds: int | None,
             say: Callable[[str], None]) -> Campaign:
    """Check and prepare the flights (module docstring)."""
    check_axis(train, axis, "training")
    check_axis(test, axis, "test")
    flights = list(train) + list(test)
    loads = tuple(ld for ld in LOADS if all(ld in f for f in flights))
    loads = tuple(ld for ld in loads if ld in AXIS_LOADS[axis]) + tuple(
        ld for ld in loads if ld not in AXIS_LOADS[axis])
    say(f"decomposing {len(train)} training and {len(test)} test flights")
    tr_sig = [signals(f, cutoff=cutoff) for f in train]
    te_sig = [signals(f, cutoff=cutoff) for f in test]
    check_excitation(tr_sig, axis)
    tr_blocks, tr_par = scoring_blocks(tr_sig, 0)
    te_blocks, te_par = scoring_blocks(te_sig, len(tr_sig))
    engine = Engine(units(tr_sig + te_sig) + units(tr_blocks + te_blocks, tr_par + te_par),
                    loads, tuple(catalogue) + tuple(probes), own=AXIS_LOADS[axis],
                    cutoff=cutoff)
    n_tr, n_te = len(tr_sig), len(te_sig)
    train_idx = tuple(range(n_tr))
    sigma2 = engine.mean_square(train_idx)
    # each family made for the training flights (its bases' range, its quasi-steady load)
    bound = tuple(e.bound(engine, train_idx) for e in catalogue)
    halves = cross_fit_folds(engine, n_tr + n_te, [p for p, _ in tr_par + te_par], n_tr,
                             folds)
    return Campaign(list(train), list(test), axis, cutoff, loads, tr_sig, te_sig, engine,
                    train_idx, tuple(range(n_tr, n_tr + n_te)),
                    tuple(range(n_tr + n_te, len(engine.units))), sigma2, halves, bound,
                    tuple(probes))
