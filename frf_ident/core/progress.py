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
How progress travels through frf_ident: one type, :data:`Progress`, in every layer.

Decision (issue 43, "one way for each parameter"): a ``progress`` parameter is always an
optional callable taking one line of text (no newline), ``Progress | None``, and ``None``
means silent. Every function that reports progress (core, bag, app) defaults to ``None``;
the wiring chooses where the lines go: the CLI passes :func:`frf_ident.app.console.say`
(stdout), the nodes their logger, tests ``lines.append``. A bag reader given a sink also
draws a tqdm bar of the bytes it reads on stderr (tqdm draws it only on a terminal) and
reports the finished scan as one line through the sink; without a sink it draws nothing.
"""
from __future__ import annotations

from typing import Callable

#: a progress sink: called with one line of text per step
Progress = Callable[[str], None]


def silent(message: str) -> None:
    """Drop a progress line (the sink that ``None`` stands for)."""


def sink(progress: Progress | None) -> Progress:
    """
    Return ``progress``, or :func:`silent` when it is None.

    Parameters
    ----------
    progress : callable or None
        A progress sink, or None for silence.

    Returns
    -------
    callable
        A sink that can be called unconditionally.

    Examples
    --------
    >>> lines = []
    >>> sink(lines.append)('read 3 files'); sink(None)('dropped'); lines
    ['read 3 files']

    """
    return silent if checked(progress) is None else progress


def checked(progress: Progress | None) -> Progress | None:
    """
    Return ``progress`` if it is None or callable.

    Raises
    ------
    TypeError
        ``progress`` is neither (e.g. the bool that bag readers once took).

    """
    if progress is not None and not callable(progress):
        raise TypeError(f'progress={progress!r}: expected a callable taking one line of text, '
                        f'or None for silence')
    return progress


__all__ = ['Progress', 'checked', 'silent', 'sink']
