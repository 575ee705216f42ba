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
A campaign's inputs: whether the command line names a campaign, its inputs expanded.

Several inputs, a folder of bags, a glob or an ``@list.txt`` file become input paths
(:func:`expand_inputs`), each with an output folder name of its own (:func:`campaign_dirs`).
"""
from __future__ import annotations

import glob
import os
from pathlib import Path
from typing import Callable, Sequence

from frf_ident.errors import FrfIdentInputError

__all__ = ['campaign_dirs', 'expand_inputs', 'FILE_SUFFIXES', 'is_bag_dir', 'is_campaign']

#: suffixes of single-file inputs a folder is searched for (besides bag directories)
FILE_SUFFIXES = ('.mcap', '.csv', '.mat')


def is_campaign(specs: Sequence[str | os.PathLike[str]],
                member: Callable[[Path], bool] | None = None) -> bool:
    """
    Return whether the inputs name a campaign rather than one input.

    Several inputs, an ``@list.txt``, a glob pattern or a folder holding bags (but not a bag
    itself) is a campaign. Anything else alone (a bag, a file, a path that does not exist
    or a folder without bags) is one input: the command keeps its single-input behaviour
    and its messages (outputs directly in ``--out``).

    Parameters
    ----------
    specs : sequence of str or path-like
        The positional inputs as given.
    member : callable, optional
        For inputs that are folders of another kind (``fit``: estimate output folders):
        whether a path is one input. A folder that is one is one input; a folder holding
        some is a campaign. Default: bags and data files as above.

    Returns
    -------
    bool
        True for a campaign.

    """
    if len(specs) != 1:
        return True
    text = os.fspath(specs[0])
    if text.startswith('@') or glob.has_magic(text):
        return True
    p = Path(text)
    if member is not None:
        return p.is_dir() and not member(p) and any(member(q) for q in p.iterdir())
    return p.is_dir() and not is_bag_dir(p) and any(_is_input(q) for q in p.iterdir())


def is_bag_dir(p: Path) -> bool:
    """
    Return whether the folder ``p`` is one bag: it has metadata.yaml or MCAP files of its own.

    A rosbag2 folder whose metadata.yaml was lost (a recorder killed) still holds its split
    .mcap files, and the bag reader reads them in order as one bag: such a folder is one
    input, never a campaign of its files.
    """
    return (p / 'metadata.yaml').is_file() or any(p.glob('*.mcap'))


def _is_input(p: Path) -> bool:
    return (p / 'metadata.yaml').is_file() or (p.is_file() and p.suffix in FILE_SUFFIXES)


def _expand_one(spec: str, member: Callable[[Path], bool] | None = None) -> list[Path]:
    if spec.startswith('@'):
        lst = Path(spec[1:])
        try:
            lines = lst.read_text().splitlines()
        except OSError as err:
            raise FrfIdentInputError(f'{spec}: cannot read the list file ({err.strerror}); '
                                     f'expected one input path per line') from err
        # relative entries are relative to the list file, so a list travels with its bags
        return [q for s in lines if s.strip() and not s.lstrip().startswith('#')
                for q in _expand_one(str(lst.parent / s.strip()), member)]
    if glob.has_magic(spec):
        hits = sorted(Path(h) for h in glob.glob(spec))
        if not hits:
            raise FrfIdentInputError(f'{spec}: the pattern matches nothing; expected bags')
        return hits
    p = Path(spec)
    if not p.exists():
        raise FrfIdentInputError(f'{spec}: no such bag, file or folder')
    if member is not None and p.is_dir():
        if member(p):
            return [p]
        found = sorted(q for q in p.iterdir() if member(q))
        if not found:
            what = (member.__doc__ or member.__name__).strip().splitlines()[0]
            raise FrfIdentInputError(f'{spec}: a folder without inputs (none of its entries '
                                     f'passes {member.__name__}: {what})')
        return found
    if p.is_dir() and not (p / 'metadata.yaml').is_file():
        found = sorted(q for q in p.iterdir() if _is_input(q))
        if not found:
            raise FrfIdentInputError(f'{spec}: a folder without bags (expected bag folders '
                                     f'with metadata.yaml or {", ".join(FILE_SUFFIXES)} files)')
        return found
    return [p]


def expand_inputs(specs: Sequence[str | os.PathLike[str]],
                  member: Callable[[Path], bool] | None = None) -> list[Path]:
    """
    Expand paths, folders of bags, globs and ``@list.txt`` files into input paths.

    Parameters
    ----------
    specs : sequence of str or path-like
        Each a bag or file, a folder holding bags (bag folders and .mcap/.csv/.mat files,
        sorted by name), a glob pattern (sorted), or ``@FILE``: a text file with one such
        entry per line (blank lines and ``#`` comments skipped; relative entries are taken
        relative to the list file).
    member : callable, optional
        Inputs of another kind (see :func:`is_campaign`): a folder is one input when
        ``member`` says so, else its entries that are; its docstring names them in errors.

    Returns
    -------
    list of Path
        The inputs in the order given, each once.

    Raises
    ------
    FrfIdentInputError
        An entry that does not exist, a pattern or folder that holds nothing, an unreadable
        list file (one line naming it).

    """
    seen: dict[Path, None] = {}
    for s in specs:
        for p in _expand_one(os.fspath(s), member):
            seen.setdefault(p, None)
    return list(seen)


def campaign_dirs(inputs: Sequence[Path]) -> list[str]:
    """
    Return one output folder name per input: its name without suffix, made unique.

    Parameters
    ----------
    inputs : sequence of Path
        The expanded inputs.

    Returns
    -------
    list of str
        ``bag_a``, ``bag_b``...; a name that repeats (bags of the same name in different
        folders) gets ``_2``, ``_3``... in input order.

    """
    names: list[str] = []
    used: set[str] = set()
    for p in inputs:
        base = p.name[:-len(p.suffix)] if p.suffix in FILE_SUFFIXES else p.name
        name, k = base or 'input', 1
        while name in used:
            k += 1
            name = f'{base}_{k}'
        used.add(name)
        names.append(name)
    return names
