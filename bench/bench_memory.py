"""What a server keeps after a class has gone: the shared caches, and the rest.

One session (no websocket) is moved through many settings, as a class of students
dragging r and c does, until the shared diagram cache is at its bound; then the session
is closed. Reported: the process's resident memory (VmRSS) at the start, after the
settings, after the session is closed and collected, and after the shared caches (the
diagrams of ``app.diagram`` and the scenes of ``app.compute``) are dropped and freed
memory handed back to the system (``malloc_trim``), with the bytes the diagram cache
held. The difference between the last two is what the caches cost; what remains above
the start is memory the allocator keeps or the process has grown by otherwise.

    .venv/bin/python bench/bench_memory.py [--settings 200]
"""
from __future__ import annotations

import argparse
import ctypes
import gc
import itertools
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def trim() -> None:
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):      # not glibc: nothing to hand back explicitly
        pass


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--settings", type=int, default=200,
                    help="distinct (r, c) settings visited (200: beyond the cache's 128)")
    args = ap.parse_args(argv)
    import panel as pn

    from app import diagram
    from app.explorer import Explorer

    pn.extension(notifications=False)
    e = Explorer(args={})
    assert e.diagram.job.done.wait(120)
    e.release_links()
    del e
    trim()
    start = rss_mb()

    e = Explorer(args={})
    assert e.diagram.job.done.wait(120)
    grid = itertools.product([round(0.30 + 0.01 * i, 2) for i in range(66)],
                             [round(0.02 + 0.01 * j, 2) for j in range(9)])
    tic = time.perf_counter()
    for r, c in itertools.islice(grid, args.settings):
        e.settings.param.update(r=r, c=c)
        assert e.diagram.job.done.wait(120), (r, c)
    elapsed = time.perf_counter() - tic
    full = rss_mb()
    cached = sum(s.nbytes for s in diagram.CACHE._items.values())
    items = len(diagram.CACHE)
    e.release_links()
    del e
    trim()
    closed = rss_mb()
    diagram.CACHE.clear()
    pn.state.clear_caches()
    trim()
    dropped = rss_mb()
    print(f"{args.settings} settings in {elapsed:.0f} s; diagram cache: {items} diagrams, "
          f"{cached / 2**20:.1f} MB of arrays (bound {diagram.CACHE_BYTES / 2**20:.0f} MB, "
          f"{diagram.CACHE_ITEMS} items)")
    print(f"RSS: start {start:.0f} MB; after the settings {full:.0f} MB; session closed "
          f"{closed:.0f} MB (+{100 * (closed / start - 1):.0f} %); caches dropped "
          f"{dropped:.0f} MB (+{100 * (dropped / start - 1):.0f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
