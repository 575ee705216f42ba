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
Where the command line's output goes: the console at INFO, ``DIR/<command>.log`` at DEBUG.

The one mechanism for output (docs/CONTRACT.md §1): library code logs with
``logging.getLogger(__name__)``, stage summaries at INFO and search traces at DEBUG. For one
command :func:`configured` installs a console handler on stdout with the plain message (DEBUG
with ``-v``, warnings only with ``-q``) and, for a command with an output directory, a file
handler that writes every DEBUG line to ``DIR/<command>.log``; it removes both when the command
ends, so a process (a test) may run several commands.
"""
from __future__ import annotations

from contextlib import contextmanager
import logging
import os
from pathlib import Path
import sys
from typing import Iterator

from frf_ident.app.console import set_bars

__all__ = ['PACKAGE_LOGGER', 'configured']

#: the logger every module of the package logs under (``logging.getLogger(__name__)``)
PACKAGE_LOGGER = 'frf_ident'
#: the log file's line: time, level and module, for reading a trace afterwards
FILE_FORMAT = '%(asctime)s %(levelname)-7s %(name)s: %(message)s'


class _Stdout(logging.StreamHandler):
    """A stream handler on whatever ``sys.stdout`` is when a line is written."""

    def emit(self, record: logging.LogRecord) -> None:
        self.setStream(sys.stdout)
        super().emit(record)


class _DirFile(logging.FileHandler):
    """
    A file handler that writes nothing until the command has created its output directory.

    Lines logged before the directory exists are held and written first; a command refused
    before it creates the directory (exit 2, "nothing was written") leaves no log behind.
    """

    def __init__(self, filename: Path) -> None:
        super().__init__(filename, mode='w', encoding='utf-8', delay=True)
        self.held: list[logging.LogRecord] = []

    def _ready(self) -> bool:
        return self.stream is not None or os.path.isdir(os.path.dirname(self.baseFilename))

    def emit(self, record: logging.LogRecord) -> None:
        if not self._ready():
            self.held.append(record)
            return
        while self.held:
            super().emit(self.held.pop(0))
        super().emit(record)

    def close(self) -> None:
        if self.held and self._ready():
            for record in self.held:
                super().emit(record)
        self.held = []
        super().close()


@contextmanager
def configured(*, verbose: bool = False, quiet: bool = False,
               log_file: str | os.PathLike[str] | None = None) -> Iterator[logging.Logger]:
    """
    Route the package's log records to the console (and a file) while the block runs.

    Parameters
    ----------
    verbose : bool, optional
        Show DEBUG lines (search traces) on the console (``-v``).
    quiet : bool, optional
        Show only warnings and errors on the console and no progress bars (``-q``).
    log_file : path-like, optional
        Write every line from DEBUG up to this file (replaced), once the command has created
        the file's directory (a command refused before that leaves nothing behind).

    Yields
    ------
    logging.Logger
        The package logger.

    """
    logger = logging.getLogger(PACKAGE_LOGGER)
    console = _Stdout(sys.stdout)
    console.setFormatter(logging.Formatter('%(message)s'))
    console.setLevel(logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO)
    handlers: list[logging.Handler] = [console]
    if log_file is not None:
        file = _DirFile(Path(log_file))
        file.setFormatter(logging.Formatter(FILE_FORMAT))
        file.setLevel(logging.DEBUG)
        handlers.append(file)
    # a logging.config.dictConfig elsewhere in the process (e.g. import-linter's, in the test
    # suite) disables every logger that existed before it; the command owns its output
    for name, existing in logging.root.manager.loggerDict.items():
        if name.split('.')[0] == PACKAGE_LOGGER and isinstance(existing, logging.Logger):
            existing.disabled = False
    old_level = logger.level
    logger.setLevel(min(h.level for h in handlers))
    for h in handlers:
        logger.addHandler(h)
    set_bars(False if quiet else None)
    try:
        yield logger
    finally:
        set_bars(None)
        for h in handlers:
            logger.removeHandler(h)
            h.close()
        logger.setLevel(old_level)
