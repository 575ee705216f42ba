"""The ``frf-ident`` command line (see :mod:`frf_ident.cli.main`)."""
from frf_ident.cli.main import main

__all__ = ['main']
