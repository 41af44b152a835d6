"""Independent flights spread over the available devices (CPU cores, GPUs), of this process
or, after [`initialize_distributed`][fwid.estimate._distributed.initialize_distributed], of
every process of a cluster (`jax.devices()` is then the global list)."""

from __future__ import annotations

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec


def device_count() -> int:
    """The devices of JAX's default backend, over all processes (CPU devices: see
    `fwid/__init__.py`)."""
    return len(jax.devices())


#: Work [flop] at which jaxlib's CPU LAPACK kernels split a batch of small matrices over
#: XLA's intra-op threads (`GetLapackBatchChunkSize` in jaxlib's `lapack_kernels.cc`).
LAPACK_SPLIT_FLOPS = 200_000


def flights_per_call(n_params: int) -> int | None:
    """The most flights one batched call may fit per CPU device (`None`: no limit).

    A batched LAPACK call of `B` matrices `p x p` costs about `B p^3`; from
    `LAPACK_SPLIT_FLOPS` on, jaxlib hands the matrices to XLA's intra-op threads and blocks
    the thread it runs on until they are done. When every device's program does so at once
    (one CPU device per core, all pool threads blocked) nothing is left to do the work and
    the process hangs: 128 flights of the 16-parameter model on this repository's 2-core
    machine did (jax 0.10.2), in the 16 x 16 solves. Below the threshold the solves run where
    they are called. Half the threshold, for a margin."""
    if jax.default_backend() != "cpu":
        return None
    return max(1, (LAPACK_SPLIT_FLOPS // 2) // max(n_params, 1) ** 3)


def padded_count(n_flights: int) -> int:
    """`n_flights` rounded up to a multiple of the device count, so that every device gets
    the same number of flights (the extra ones are copies whose results are dropped)."""
    d = device_count()
    if n_flights < 2 or d < 2:
        return n_flights
    return -(-n_flights // d) * d


def flight_mesh(n_flights: int) -> Mesh | None:
    """A one-axis mesh, `"flights"`, over all devices when `n_flights` splits evenly over
    two or more of them; `None` otherwise (run on one device)."""
    d = device_count()
    if d < 2 or n_flights < 2 or n_flights % d:
        return None
    return Mesh(np.array(jax.devices()), ("flights",))


def spans_processes(mesh: Mesh | None) -> bool:
    """Whether `mesh` has devices of other processes (a `jax.distributed` cluster)."""
    return mesh is not None and jax.process_count() > 1


def onto_mesh(tree, mesh: Mesh | None):
    """Host arrays with a leading flight axis, the same on every process, as global arrays
    split over `mesh`'s `"flights"` axis (each process places only its own devices' share).
    Unchanged on one process: `jit` places them itself."""
    if not spans_processes(mesh):
        return tree
    sharding = NamedSharding(mesh, PartitionSpec("flights"))

    def place(a):
        a = np.asarray(a)
        return jax.make_array_from_callback(a.shape, sharding, lambda idx: a[idx])

    return jax.tree.map(place, tree)


def to_host(tree, mesh: Mesh | None):
    """The arrays of `tree` (computed over `mesh`) as numpy arrays. When `mesh` spans
    processes the arrays must be replicated (gathered in the program that made them): each
    process reads its own first device's copy."""
    if not spans_processes(mesh):
        return jax.device_get(tree)
    return jax.tree.map(lambda a: np.asarray(a.addressable_data(0)), tree)
