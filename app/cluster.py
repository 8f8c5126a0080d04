"""Where the research views compute: a Dask cluster, or this server's threads.

``IMPACT_DASK_SCHEDULER=tcp://host:8786`` (read as each research picture starts) names a
scheduler; the regime map, the basins and the boundary curves then run
on its workers (``impactlib.sweeps.distributed``: the same results as on the server's
threads). Without the setting nothing changes. The server connects once, from a research
worker thread (never the event loop); an address that cannot be reached, or a server
without the ``dask`` extra, is said once in the log (one WARNING line) and on every
picture's status line, and the pictures are computed on the server's threads. A cluster
that fails during a picture fails that picture with a message saying so
(``failure_text``); the next picture connects again, and computes here (with the note)
if the scheduler is gone.
"""
from __future__ import annotations

import logging
import os
import threading

log = logging.getLogger(__name__)

ENV = "IMPACT_DASK_SCHEDULER"
CONNECT_TIMEOUT = 5.0     # seconds to reach the scheduler
#: ``distributed.Client.status`` of a client that lost its scheduler (trying to reach it
#: again, which it gives up on by itself, or closed): a new connection is made instead.
LOST = ("connecting", "closing", "closed")


class Cluster:
    """The process's connection to the scheduler at ``address`` (made on first use)."""

    def __init__(self, address: str):
        self.address = address
        self._lock = threading.Lock()
        self._client = None
        self.error = ""            # why the cluster is not used ("" while it is or untried)
        self._tried = False

    def client(self):
        """The ``distributed.Client``, or None (the reason is in ``error``). A client that
        lost its scheduler is dropped and the connection made again."""
        with self._lock:
            if self._client is not None and self._client.status in LOST:
                log.warning("%s=%r: the Dask scheduler stopped answering; connecting again",
                            ENV, self.address)
                self._client, self._tried, self.error = None, False, ""
            if not self._tried:
                self._tried = True
                self._client, self.error = _connect(self.address)
                if self.error:
                    log.warning("%s; the research views compute on this server",
                                self.error)
            return self._client

    def where(self) -> str:
        """Where the pictures are computed, for a status line."""
        if self._client is not None:
            return f"on the Dask cluster at {self.address}"
        if self.error:
            return f"on this server ({self.error})"
        return "on this server"

    def close(self) -> None:
        with self._lock:
            if self._client is not None:
                self._client.close()
            self._client, self._tried, self.error = None, False, ""


def _connect(address: str):
    """(client, "") or (None, the reason in words, naming the setting and its value)."""
    head = f"{ENV}={address!r}"
    try:
        import distributed
    except ImportError:
        return None, (f"{head} is set but the dask extra is not installed "
                      "(pip install impact-explorer[dask])")
    try:
        client = distributed.Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except Exception as exc:          # unreachable, refused, not an address
        return None, (f"{head}: no Dask scheduler reached ({type(exc).__name__}: "
                      f"{str(exc)[:200]})")
    return client, ""


_LOCK = threading.Lock()
_SHARED: dict[str, Cluster] = {}


def current() -> Cluster | None:
    """The cluster named by ``IMPACT_DASK_SCHEDULER`` (None when it is not set)."""
    address = os.environ.get(ENV, "").strip()
    if not address:
        return None
    with _LOCK:
        if address not in _SHARED:
            _SHARED[address] = Cluster(address)
        return _SHARED[address]


def failure_text(exc: Exception, client) -> str:
    """What a view says when its picture failed with ``exc``: a picture computed on a
    cluster (``client`` not None) that failed other than by the core refusing its
    input (ValueError) lost its cluster midway."""
    head = f"{type(exc).__name__}: {str(exc)[:200]}"
    if client is None or isinstance(exc, ValueError):
        return head
    return ("the Dask cluster stopped answering during the picture "
            f"({head}); compute again: the next picture connects again, or is computed "
            "on this server if the cluster is gone")


def client():
    """(client or None, where): what a research job computes with, and the words for
    its status line ("" when no cluster is set)."""
    cluster = current()
    if cluster is None:
        return None, ""
    return cluster.client(), cluster.where()
