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
The ``--out`` of every command: checked before any work, a command's own outputs replaced.

:func:`check_out` is the one rule: a bag path must be new; an output directory may exist but
must not already hold the command's outputs unless ``--overwrite`` is given; either way the
path must be creatable and writable. :func:`clear_outputs` removes a command's own files of an
earlier run just before it writes the new ones (never anything else).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

from frf_ident.errors import FrfIdentInputError

__all__ = ['check_out', 'clear_outputs']


def _refuse(out: str, what: str) -> FrfIdentInputError:
    return FrfIdentInputError(f'--out {out!r}: {what} (nothing was written)')


def check_out(out: str | os.PathLike[str], *, outputs: Sequence[str] | None,
              overwrite: bool) -> Path:
    """
    Check an output path before any work is done; return it as a Path.

    Parameters
    ----------
    out : str or path-like
        The ``--out`` as given (an empty string is refused, not read as the current directory).
    outputs : sequence of str or None
        None: ``out`` is a bag directory to create, an existing path is refused. Otherwise
        ``out`` is an output directory (created later if missing) and these are the names of
        the files the command writes into it: a directory already holding one of them is
        refused unless ``overwrite``.
    overwrite : bool
        Accept a directory holding ``outputs`` of an earlier run (``--overwrite``).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    FrfIdentInputError
        One line naming the path and what is wrong: empty, a file (or anything but a directory)
        where a directory is wanted, a parent that is not a directory, not writable, or
        holding a bag or earlier outputs.

    """
    text = os.fspath(out)
    if not text.strip():
        raise FrfIdentInputError(f'--out {text!r}: empty; expected a directory path')
    path = Path(text)
    present = path.exists() or path.is_symlink()
    if present and outputs is None:
        raise FrfIdentInputError(f'--out {text!r} already exists; choose a new bag path '
                                 f'(nothing was overwritten)')
    if present and not path.is_dir():
        raise _refuse(text, 'is a file, not a directory; expected an output directory')
    # the nearest existing directory is where the path gets created (or the path itself)
    base = path if present else next(
        (p for p in path.parents if p.exists() or p.is_symlink()), Path('.'))
    if not base.is_dir():
        raise _refuse(text, f'{str(base)!r} is a file, not a directory; expected a path '
                            f'inside a directory')
    if not os.access(base, os.W_OK | os.X_OK):
        raise _refuse(text, f'directory {str(base)!r} is not writable')
    held = [n for n in outputs or () if (path / n).exists() or (path / n).is_symlink()]
    if held and not overwrite:
        raise FrfIdentInputError(
            f'--out {text!r} already holds {", ".join(held)} of an earlier run; choose a new '
            f'directory or pass --overwrite to replace them (nothing was overwritten)')
    for n in held:
        if (path / n).is_dir() and not (path / n).is_symlink():
            raise _refuse(text, f'{n} is a directory; expected the file of an earlier run')
    return path


def clear_outputs(out: Path, outputs: Sequence[str]) -> None:
    """
    Remove a command's own output files of an earlier run from ``out`` (nothing else).

    Called just before the new files are written, so an earlier run's file the new one does
    not write (a figure of another mode) does not stay beside the new report.

    Parameters
    ----------
    out : Path
        The output directory (may not exist yet).
    outputs : sequence of str
        Names of the files the command writes into ``out``.

    """
    for n in outputs:
        p = Path(out) / n
        if p.is_symlink() or p.is_file():
            p.unlink()
