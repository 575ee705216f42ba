"""
Data exchange with other tools, model files and the package's data files.

Import measured tables (CSV/MAT) as recordings, export frequency responses (python-control,
MATLAB idfrd, CSV, JSON); see README_io.md.
"""
from .export import from_control, read_frf, to_control, write_frf

__all__ = ['from_control', 'import_table', 'load_map', 'read_frf', 'to_control', 'write_frf']


def __getattr__(name: str):  # the importer pulls in yaml/scipy.io only when used
    """Load ``import_table`` and ``load_map`` from :mod:`frf_ident.io.importer` on first use."""
    if name in ('import_table', 'load_map'):
        from . import importer
        return getattr(importer, name)
    raise AttributeError(name)
