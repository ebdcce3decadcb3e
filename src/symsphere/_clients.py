"""Dask clients for :mod:`symsphere.distributed`: a remote scheduler's, a local cluster's, and closing them.

Public through :mod:`symsphere.distributed` (``connect``, ``local_client``, ``close_client``).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from typing import TYPE_CHECKING

from ._validation import check_client, check_count, check_positive_real, short_repr

if TYPE_CHECKING:  # not at import: dask loads only when used
    from distributed import Client

__all__ = ["client_or_local", "close_client", "connect", "local_client"]


def connect(address: str, *, timeout: float = 10) -> Client:
    """A ``distributed.Client`` for the scheduler at *address*, or a clear error within *timeout* seconds.

    Parameters
    ----------
    address : str
        The scheduler's address, as ``dask scheduler`` prints it (``tcp://HOST:8786``).
    timeout : float
        Seconds to wait for the scheduler.

    Returns
    -------
    distributed.Client
        Pass it as ``client=`` to :func:`~symsphere.distributed.integrate` and :func:`~symsphere.distributed.render`, or compute the
        arrays of :func:`~symsphere.distributed.sample_sphere` with it; close it with :func:`close_client`
        (the cluster keeps running).

    Raises
    ------
    ConnectionError
        If no scheduler answers at *address* within *timeout*.

    Examples
    --------
    A small cluster in this process stands in for ``dask scheduler`` and ``dask worker``:

    >>> from distributed import LocalCluster
    >>> from symsphere.distributed import close_client, connect
    >>> cluster = LocalCluster(n_workers=1, processes=False, dashboard_address=":0")  # any free port
    >>> client = connect(cluster.scheduler_address)
    >>> len(client.scheduler_info()["workers"])
    1
    >>> close_client(client)
    >>> cluster.close()
    """
    from distributed import Client

    if not isinstance(address, str) or not address:
        raise TypeError(
            f"'address' must be the scheduler's address as a string (tcp://HOST:8786), got {short_repr(address)}; "
            "for a cluster on this machine use local_client()"
        )
    timeout = check_positive_real(timeout, "timeout")
    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError) as exc:
        raise ConnectionError(
            f"could not reach the Dask scheduler at {address!r} within {timeout} s "
            f"({type(exc).__name__}: {exc}); start one with 'dask scheduler' and workers with "
            f"'dask worker {address}'"
        ) from exc


def local_client(workers: int | None = None) -> Client:
    """A ``LocalCluster`` client: *workers* single-threaded worker processes (default: one per core).

    Parameters
    ----------
    workers : int, optional
        Worker processes, each with one thread (the kernels of a task run single-threaded).

    Returns
    -------
    distributed.Client
        A client of its own cluster; close both with :func:`close_client`.

    Examples
    --------
    >>> from symsphere.distributed import close_client, integrate, local_client
    >>> client = local_client(workers=1)
    >>> len(client.scheduler_info()["workers"])
    1
    >>> result = integrate(lambda d: d[:, 2] ** 2, client=client, n=48 * 4, rng=1)
    >>> round(result.integral, 10)                     # 4 pi / 3: exact from one orbit
    4.1887902048
    >>> close_client(client)
    """
    from distributed import Client, LocalCluster

    workers = (os.cpu_count() or 1) if workers is None else check_count(workers, "workers")
    # the scheduler's HTTP server on a free port (None would still take 8787, and warn if it is taken)
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    return Client(cluster)


def close_client(client: Client) -> None:
    """Close *client*, and its cluster too if it runs one of its own (as :func:`local_client`'s does).

    A client of a remote scheduler (:func:`connect`) is closed and its cluster left running.

    Parameters
    ----------
    client : distributed.Client

    Examples
    --------
    >>> from symsphere.distributed import close_client, local_client
    >>> client = local_client(1)
    >>> cluster = client.cluster
    >>> close_client(client)
    >>> client.status, cluster.status.name
    ('closed', 'closed')
    """
    if check_client(client) is None:
        raise TypeError("'client' must be a distributed.Client, got None")
    cluster = getattr(client, "cluster", None)  # None for a client of a remote scheduler
    client.close()
    if cluster is not None:
        cluster.close()


@contextlib.contextmanager
def client_or_local(client: Client | None) -> Iterator[Client]:
    given: Client | None = check_client(client)
    if given is not None:
        yield given
        return
    owned = local_client()
    try:
        yield owned
    finally:
        close_client(owned)
