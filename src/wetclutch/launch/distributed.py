"""Sweeps on a ``dask.distributed`` cluster.

A sweep (the launches of a verification) is a list of independent items. :func:`map_batches`
maps a function over them on an existing cluster: the items go out in batches (one task a
batch, so that a task's overhead is spread over several launches), every worker first warms
its numba cache (:meth:`distributed.Client.run`, before the map), and the results come back
in the order of the items. Each item carries everything its result depends on (a verification
sample has its own noise seed), so the results are bit for bit those of a local run, whatever
the number of workers and however the items fall into batches.

The scheduler is the ``--scheduler`` option or, without it, the environment variable
``DASK_SCHEDULER_ADDRESS``; with neither, sweeps run locally (:func:`scheduler_address`).
"""

from __future__ import annotations

import contextlib
import math
import os
import socket
from collections.abc import Callable, Sequence
from typing import Any

from ..errors import WetclutchError

#: environment variable naming the scheduler when no ``--scheduler`` is given
ENV_SCHEDULER = "DASK_SCHEDULER_ADDRESS"
#: batches per worker thread: enough to balance launches of unequal length, few enough to keep tasks long
BATCHES_PER_THREAD = 4
#: seconds to wait for the scheduler before giving up
CONNECT_TIMEOUT_S = 10


def scheduler_address(option: str | None) -> str | None:
    """The scheduler to use: the option, else ``$DASK_SCHEDULER_ADDRESS``, else None (run locally)."""
    address = option if option is not None else os.environ.get(ENV_SCHEDULER, "")
    address = address.strip()
    return address or None


def split(items: Sequence[Any], n_batches: int) -> list[list[Any]]:
    """``items`` in at most ``n_batches`` contiguous batches of nearly equal size, in order."""
    if not items:
        return []
    size = math.ceil(len(items) / max(1, n_batches))
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def _apply(fn: Callable[[Any], Any], batch: list[Any]) -> list[Any]:
    # one task: the items of a batch one after another on one worker
    return [fn(item) for item in batch]


def _source(address: str) -> str:
    """What named ``address``: the environment variable if it holds it, else the option."""
    return ENV_SCHEDULER if os.environ.get(ENV_SCHEDULER, "").strip() == address else "--scheduler"


def _greets(address: str) -> bool:
    """Whether a server at a ``tcp://`` ``address`` that accepts a connection sends something first, as a dask
    scheduler sends its handshake at once. Another server (a web server waits for a request) would leave the client
    waiting for a reply that never comes, past its own timeout. True where this cannot tell (another protocol, no
    connection: the client's own error says why)."""
    from distributed.comm import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme != "tcp":
            return True
        host, port = parse_host_port(location)
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S) as sock:
            sock.settimeout(CONNECT_TIMEOUT_S)
            return bool(sock.recv(1))
    except TimeoutError:
        return False
    except (OSError, ValueError, TypeError):
        return True


def connect(address: str, source: str | None = None) -> Any:
    """A client of the scheduler at ``address``; a one-line error if it cannot be reached.

    Parameters
    ----------
    address
        The scheduler's address, e.g. ``tcp://10.0.0.5:8786``.
    source
        What gave the address, named in the error (default: :data:`ENV_SCHEDULER` if the
        environment variable holds ``address``, else ``--scheduler``).

    Returns
    -------
    distributed.Client
        A connected client (not the default one); close it after use.

    Raises
    ------
    WetclutchError
        The address is malformed or no scheduler answers there within :data:`CONNECT_TIMEOUT_S`.
    """
    source = source or _source(address)
    try:
        from distributed import Client
    except ImportError as e:  # pragma: no cover - a dependency of the package
        raise WetclutchError(f"{source} needs dask.distributed installed ({e})") from None
    # made apart from its start, so that a client whose start fails can still be closed here: left to its
    # finalizer, it waits for its event loop at exit and prints a traceback long after the error
    if not _greets(address):
        raise WetclutchError(f"{source}: no dask scheduler answers at {address!r} (a server there accepted the "
                             f"connection but sent no dask handshake within {CONNECT_TIMEOUT_S} s)")
    client = Client.__new__(Client)
    try:
        client.__init__(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except BaseException as e:
        with contextlib.suppress(Exception):
            client.close(timeout=CONNECT_TIMEOUT_S)
        if isinstance(e, (OSError, TimeoutError, ValueError)):
            raise WetclutchError(f"{source}: cannot reach a dask scheduler at {address!r} ({e})") from None
        raise
    return client


def map_batches(fn: Callable[[Any], Any], items: Sequence[Any], scheduler: str, warm: Callable[[], Any] | None = None,
                batch_size: int | None = None, on_batch: Callable[[int], None] | None = None) -> list[Any]:
    """``[fn(item) for item in items]`` computed on the cluster at ``scheduler``.

    Parameters
    ----------
    fn
        A picklable function of one item (a module-level function or a ``functools.partial`` of one).
    warm
        Run once on every worker before the map (compiles or loads the numba cache there).
    batch_size
        Items per task; default: the items spread over :data:`BATCHES_PER_THREAD` tasks per worker thread.
    on_batch
        Called with the number of items of each batch as its results arrive, in order (progress).
    """
    if not items:
        return []
    client = connect(scheduler)
    try:
        if warm is not None:
            client.run(warm)
        threads = max(1, sum(client.nthreads().values()))
        n_batches = math.ceil(len(items) / batch_size) if batch_size else threads * BATCHES_PER_THREAD
        batches = split(items, n_batches)
        futures = client.map(_apply, [fn] * len(batches), batches, pure=False)
        results = []
        for batch, fut in zip(batches, futures):
            results.append(fut.result())
            if on_batch is not None:
                on_batch(len(batch))
        return [r for batch in results for r in batch]
    finally:
        client.close()
