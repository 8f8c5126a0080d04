"""Progress and cancellation of long sweeps: ``progress`` is None/False, True (a tqdm bar,
in a terminal or a notebook) or a callable ``progress(done, total)`` called after each
chunk (monotone, the last call has done == total unless cancelled); ``cancel`` is a
``threading.Event``: once set, no further chunk starts."""
from __future__ import annotations


def reporter(progress, total: int, what: str):
    """(update(done), close()) for a progress setting: None/False, True (tqdm) or callable."""
    if progress is None or progress is False:
        return (lambda done: None), (lambda: None)
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, unit=what)

        def update(done):
            bar.update(done - bar.n)
        return update, bar.close
    if not callable(progress):
        raise ValueError(f"progress={progress!r} must be True, False, None or a callable "
                         "progress(done, total)")
    return (lambda done: progress(done, total)), (lambda: None)


def stopped(cancel) -> bool:
    return cancel is not None and cancel.is_set()

