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
The package layout.

Layers (import-linter contracts in .importlinter), no import cycle between modules, and no
module importing another module's private name.
"""
import ast
from pathlib import Path

import grimp
import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = 'frf_ident'


@pytest.fixture(scope='module')
def graph():
    return grimp.build_graph(PACKAGE, include_external_packages=False, cache_dir=None)


def import_cycles(graph) -> list[list[str]]:
    """
    Return the strongly connected components of more than one module.

    A package's own re-exports of its submodules count: they would be a cycle too.
    """
    mods = sorted(graph.modules)
    index = {m: i for i, m in enumerate(mods)}
    rows, cols = [], []
    for m in mods:
        for t in graph.find_modules_directly_imported_by(m):
            if t in index:
                rows.append(index[m])
                cols.append(index[t])
    adj = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(mods), len(mods)))
    n, labels = connected_components(adj, directed=True, connection='strong')
    comps = [[mods[i] for i in np.flatnonzero(labels == k)] for k in range(n)]
    return [c for c in comps if len(c) > 1]


def private_imports(root: Path = ROOT) -> list[str]:
    """``from frf_ident.x import _name`` in a module other than frf_ident.x."""
    found = []
    for path in sorted((root / PACKAGE).rglob('*.py')):
        rel = path.relative_to(root).with_suffix('')
        parts = list(rel.parts[:-1]) if rel.name == '__init__' else list(rel.parts)
        me = '.'.join(parts)
        pkg = parts if rel.name == '__init__' else parts[:-1]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = pkg[:len(pkg) - node.level + 1]
                target = '.'.join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ''
            if not target.startswith(PACKAGE) or target == me:
                continue
            for alias in node.names:
                if alias.name.startswith('_') and not alias.name.startswith('__'):
                    found.append(f'{me}:{node.lineno} imports {target}.{alias.name}')
    return found


def test_no_import_cycles(graph):
    assert import_cycles(graph) == []


def test_cycle_detector_sees_a_cycle():
    g = grimp.ImportGraph()
    for m in ('p', 'p.a', 'p.b', 'p.c'):
        g.add_module(m)
    g.add_import(importer='p.a', imported='p.b')
    g.add_import(importer='p.b', imported='p.a')
    g.add_import(importer='p.c', imported='p.a')
    assert import_cycles(g) == [['p.a', 'p.b']]


def test_no_private_names_across_modules():
    assert private_imports() == []


def test_private_detector_sees_one(tmp_path):
    (tmp_path / PACKAGE / 'sub').mkdir(parents=True)
    (tmp_path / PACKAGE / '__init__.py').write_text('')
    (tmp_path / PACKAGE / 'sub' / '__init__.py').write_text('from .a import _ok_in_pkg\n')
    (tmp_path / PACKAGE / 'sub' / 'b.py').write_text('from frf_ident.sub.a import _bad, fine\n')
    found = private_imports(tmp_path)
    assert found == ['frf_ident.sub:1 imports frf_ident.sub.a._ok_in_pkg',
                     'frf_ident.sub.b:1 imports frf_ident.sub.a._bad']


def test_layer_contracts():
    from importlinter.cli import lint_imports
    assert lint_imports(config_filename=str(ROOT / '.importlinter'), no_cache=True) == 0


def test_core_reexports_its_public_api():
    import importlib

    import frf_ident.core as core
    for name in core.__all__:
        obj = getattr(core, name)
        assert not name.startswith('_')
        home = importlib.import_module(obj.__module__) if hasattr(obj, '__module__') else None
        assert home is not None and getattr(home, name) is obj, name
    with pytest.raises(AttributeError):
        core.not_a_name  # noqa: B018


def test_core_has_no_upward_arrows_and_diagnosis_stays_short():
    """
    Issue 53's floor plan, measured as ``python -m benchmarks layout`` measures it.

    No import from a core subpackage to a higher floor (the order of .importlinter's
    core-floors contract, checked there too); in core/diagnosis no module over 400 lines and
    no function over 80.
    """
    from benchmarks.layout import diagnosis_sizes, imports, upward_arrows
    assert upward_arrows(imports(ROOT)) == []
    big, longest, n_big, n_long = diagnosis_sizes(ROOT)
    assert (n_big, n_long) == (0, 0), (big, longest)


def test_upward_arrow_detector_sees_one(tmp_path):
    from benchmarks.layout import imports, upward_arrows
    for sub in ('model', 'simulation'):
        (tmp_path / PACKAGE / 'core' / sub).mkdir(parents=True)
        (tmp_path / PACKAGE / 'core' / sub / '__init__.py').write_text('')
    (tmp_path / PACKAGE / '__init__.py').write_text('')
    (tmp_path / PACKAGE / 'core' / '__init__.py').write_text('')
    (tmp_path / PACKAGE / 'core' / 'simulation' / 'plant.py').write_text('')
    (tmp_path / PACKAGE / 'core' / 'model' / 'schema.py').write_text(
        'from frf_ident.core.simulation.plant import x\n')
    assert upward_arrows(imports(tmp_path)) == [
        'frf_ident.core.model.schema -> frf_ident.core.simulation.plant']
