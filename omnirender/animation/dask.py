"""Frames on a Dask cluster, and the cluster set-ups the docs describe.

``render_frames(..., workers=X)`` with ``X`` a ``distributed.Client``, a
scheduler address (``"tcp://host:8786"``, as printed by ``dask scheduler``)
or a cluster object (``LocalCluster``, ``dask_jobqueue.SLURMCluster``...).
The pickled job is scattered to every worker once (``broadcast=True``), each
task receives it from the worker's memory and unpickles it once per worker
thread; tasks are submitted with ``pure=False`` and never raise (failures come
back as results), so one bad frame never stops the others.  A worker that
dies is replaced by Dask, which re-runs its tasks.

:func:`slurm_cluster` makes a ``dask_jobqueue.SLURMCluster`` whose jobs each
run one worker process with one thread per reserved core: every thread renders
its own frames with its own scene copy and engine (POV-Ray at small sizes is
fastest run one frame per core).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from typing import Any

from .worker import FrameResult, run_frame

__all__ = ["dask_backend", "slurm_cluster", "local_cluster"]

_INSTALL = "pip install 'omnirender[distributed]'"
#: How long connecting to a scheduler address may take.
CONNECT_TIMEOUT = "20s"


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise RuntimeError(f"render_frames on Dask needs the 'distributed' package: {_INSTALL}") from None
    return distributed


def dask_backend(workers: Any) -> tuple[Any, str]:
    """(backend, description) for a Client, a scheduler address or a cluster object."""
    distributed = _distributed()
    if isinstance(workers, distributed.Client):
        client, owned = workers, False
    elif isinstance(workers, str):
        try:
            client, owned = distributed.Client(workers, timeout=CONNECT_TIMEOUT), True
        except OSError as exc:
            raise RuntimeError(
                f"render_frames: cannot reach the Dask scheduler at {workers!r}: {exc}; start one with "
                "'dask scheduler' and workers with 'dask worker ADDRESS'"
            ) from None
    elif hasattr(workers, "scheduler_address"):
        client, owned = distributed.Client(workers), True
    else:
        raise TypeError(
            "render_frames: workers must be None, an int, a distributed.Client, a Dask cluster or a scheduler "
            f"address like 'tcp://host:8786', got {type(workers).__name__}"
        )
    address = client.scheduler.address if client.scheduler is not None else "?"

    def run(key: str, payload: bytes, todo: list[tuple[int, float, str]], retries: int) -> Iterator[FrameResult]:
        try:
            shipped = client.scatter(payload, broadcast=True, hash=False)
            futures = {
                client.submit(run_frame, key, shipped, n, t, path, retries, pure=False, key=f"omnirender-{key}-{n}"): (
                    n,
                    t,
                    path,
                )
                for n, t, path in todo
            }
            for future in distributed.as_completed(futures):
                n, t, path = futures[future]
                try:
                    yield future.result()
                except Exception as exc:  # the task itself was lost (e.g. its worker died too often)
                    yield FrameResult(n, t, path, 0.0, retries + 1, f"Dask: {type(exc).__name__}: {exc}")
                future.release()
        finally:
            if owned:
                client.close()

    return run, f"Dask at {address}"


def local_cluster(workers: int = 2, threads: int = 1, **options: Any) -> Any:
    """A ``distributed.LocalCluster`` of ``workers`` processes with ``threads`` threads each (no dashboard)."""
    distributed = _distributed()
    options.setdefault("dashboard_address", None)
    options.setdefault("silence_logs", 40)  # logging.ERROR
    return distributed.LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True, **options)


def slurm_cluster(
    queue: str | None = None,
    account: str | None = None,
    cores: int = 1,
    memory: str = "4GB",
    walltime: str = "01:00:00",
    python: str | None = None,
    setup: list[str] | None = None,
    **options: Any,
) -> Any:
    """A ``dask_jobqueue.SLURMCluster`` for rendering frames (see the module docs).

    Each Slurm job runs one Dask worker process with ``cores`` CPUs and as many
    threads (frames rendered at once); ``setup`` lines run before it (``module load povray``, activating
    a venv); ``python`` is the interpreter on the compute nodes (this one by
    default).  Scale with ``cluster.scale(jobs=N)`` or ``cluster.adapt(...)``,
    then pass the cluster as ``render_frames(..., workers=cluster)``.
    ``cluster.job_script()`` shows the script ``sbatch`` receives.
    """
    try:
        from dask_jobqueue import SLURMCluster
    except ImportError:
        raise RuntimeError(f"Slurm clusters need dask-jobqueue: {_INSTALL}") from None
    options.setdefault("scheduler_options", {"dashboard": False, "dashboard_address": ":0"})
    return SLURMCluster(
        queue=queue,
        account=account,
        cores=cores,
        processes=1,
        memory=memory,
        walltime=walltime,
        python=python or sys.executable,
        job_script_prologue=list(setup or []),
        **options,
    )
