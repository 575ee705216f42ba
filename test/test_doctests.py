"""The examples in the core's docstrings run as written."""
import doctest
import importlib
import pkgutil

import frf_ident.core
import pytest


def core_modules():
    """Return the names of every module of frf_ident.core."""
    return sorted(m.name for m in pkgutil.walk_packages(frf_ident.core.__path__,
                                                        'frf_ident.core.'))


@pytest.mark.parametrize('name', [n for n in core_modules()
                                  if '>>>' in (importlib.util.find_spec(n).loader
                                               .get_source(n) or '')])
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name))
    assert result.attempted > 0 and result.failed == 0
