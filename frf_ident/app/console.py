# Copyright 2026 frf_ident developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Output for people: stage summaries through :mod:`logging`, progress bars through tqdm.

Library code logs with ``logging.getLogger(__name__)``: a stage summary (what was read, what
was found, where it was written) at INFO, search traces at DEBUG. The command line
(:mod:`frf_ident.cli.logsetup`) decides where they go; without it INFO lines stay silent, as
a library's should. :func:`say` is the ``progress`` callback of the application functions:
one INFO line. :func:`progress_bar` is the one place that decides whether a bar is drawn.
"""
from __future__ import annotations

import logging
import sys
from typing import Any, Callable, Optional, TextIO

__all__ = ['bars_enabled', 'LiveLine', 'progress_bar', 'say', 'set_bars']

_log = logging.getLogger('frf_ident.app')

#: progress bars on long work: None = on when stderr is a terminal (tqdm's own rule),
#: False = off (``frf-ident -q``)
_BARS: dict[str, bool | None] = {'enabled': None}


def say(message: str) -> None:
    """
    Log one stage line at INFO (the default ``progress`` of :mod:`frf_ident.app`).

    Parameters
    ----------
    message : str
        The line, without a newline.

    """
    _log.info(message)


def set_bars(enabled: bool | None) -> None:
    """
    Switch progress bars off (False) or back to "on when stderr is a terminal" (None).

    Parameters
    ----------
    enabled : bool or None
        False for ``-q``; None for the default.

    """
    _BARS['enabled'] = enabled


def bars_enabled() -> bool:
    """
    Return whether a progress bar is drawn now: stderr is a terminal and ``-q`` is not given.

    Returns
    -------
    bool
        True to draw.

    """
    return _BARS['enabled'] is not False and sys.stderr.isatty()


def progress_bar(total: float | None, desc: str, unit: str = 'it', **kwargs: Any):
    """
    Return a tqdm bar on stderr, disabled where :func:`bars_enabled` says so.

    Parameters
    ----------
    total : float or None
        Units of work.
    desc : str
        What the bar counts, e.g. ``'reproduce'``.
    unit : str, optional
        The unit of ``total``.
    **kwargs
        Further :class:`tqdm.tqdm` arguments (``unit_scale`` ...).

    Returns
    -------
    tqdm.tqdm
        Use as a context manager; ``update(n)`` as work is done.

    """
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False,
                disable=not bars_enabled(), **kwargs)


class LiveLine:
    """
    One updating line per run (the live estimate's status): redrawn in place on a terminal.

    On a terminal (``stream.isatty()`` and no ``-q``) each :meth:`update` rewrites the line
    after a carriage return; elsewhere (a pipe, a log file, CI) each update is one plain line
    through ``plain``. :meth:`end` closes a drawn line, so what is printed next starts on a
    line of its own.

    Parameters
    ----------
    plain : callable, optional
        Where plain lines go (default :func:`say`).
    stream : file, optional
        The terminal (default sys.stdout, where the command's lines go).

    """

    def __init__(self, plain: Optional[Callable[[str], None]] = None,
                 stream: Optional[TextIO] = None) -> None:
        self.plain = plain or say
        self.stream = stream if stream is not None else sys.stdout
        self.tty = _BARS['enabled'] is not False and self.stream.isatty()
        self.drawn = 0

    def update(self, text: str) -> None:
        """
        Show the run's newest status.

        Parameters
        ----------
        text : str
            One line, without a newline.

        """
        if not self.tty:
            self.plain(text)
            return
        pad = max(0, self.drawn - len(text))
        self.stream.write('\r' + text + ' ' * pad)
        self.stream.flush()
        self.drawn = len(text)

    def end(self) -> None:
        """Leave the drawn line as it is and move to the next line."""
        if self.tty and self.drawn:
            self.stream.write('\n')
            self.stream.flush()
        self.drawn = 0
