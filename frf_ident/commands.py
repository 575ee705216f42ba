"""Further `frf-ident` subcommands: each entry is (help, add_arguments); the handler is
registered with :func:`frf_ident.cli.command`. Kept apart from cli.py so each command's
imports load only when it runs."""
from __future__ import annotations

from typing import Callable

SUBCOMMANDS: dict[str, tuple[str, Callable]] = {}
