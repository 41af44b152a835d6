"""[`fwid.fit_each`][] over several processes or hosts: `jax.distributed` with CPU collectives.

Every process calls [`initialize_distributed`][] first (before JAX computes anything), then
`fit_each(model, flights)` with the same flights: the flights are split over the devices of
all processes (one global mesh, the same `shard_map` as on one process, `_devices.py`), and
every process gets every flight's result.
"""

from __future__ import annotations


def initialize_distributed(coordinator: str | None = None, num_processes: int | None = None,
                           process_id: int | None = None, *, local_devices: int | None = None,
                           collectives: str = "gloo") -> None:
    """Join this process to a JAX cluster so that [`fwid.fit_each`][] spans all processes.

    `coordinator` (`"host:port"` of process 0), `num_processes` and `process_id` (0 ..
    `num_processes - 1`) are those of `jax.distributed.initialize`; left as `None`, JAX
    detects them from a cluster manager (Slurm, Open MPI, ...). `local_devices` sets this
    process's CPU device count (default: fwid's one per core, or `FWID_CPU_DEVICES`).
    `collectives` is JAX's CPU collectives implementation (`jax_cpu_collectives_implementation`:
    `"gloo"`, in every jaxlib; `"mpi"` needs an MPI library); on GPUs JAX uses NCCL itself.

    Call it before JAX computes anything (JAX refuses afterwards, a `RuntimeError`).
    """
    import jax

    jax.config.update("jax_cpu_collectives_implementation", collectives)
    if local_devices is not None:
        jax.config.update("jax_num_cpu_devices", int(local_devices))
    jax.distributed.initialize(coordinator, num_processes, process_id)
