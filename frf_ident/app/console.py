"""Progress output of the application functions (one line each, flushed at once)."""
from __future__ import annotations

__all__ = ['say']


def say(message: str) -> None:
    """
    Print one progress line and flush it (the default ``progress`` of :mod:`frf_ident.app`).

    Parameters
    ----------
    message : str
        The line, without a newline.

    """
    print(message, flush=True)
