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
The house's floor plan in numbers, now and at an earlier revision, side by side.

``python -m benchmarks layout`` (``FRF_LAYOUT_BEFORE=<rev>``, default the revision before issue
53's floor plan): import cycles between modules, upward arrows between core's subpackages (in
the order of .importlinter's core-floors contract), core/diagnosis' largest module and
longest function and how many exceed 400 lines / 80 lines, the package's modules over 600 lines
(the house rule: one concept per module), public functions that return a ``dict``, and the
distinct ``meta`` keys the code reads and the layers that read them.
"""
from __future__ import annotations

import ast
import os
from pathlib import Path
import subprocess
import tempfile

ROOT = Path(__file__).resolve().parents[1]
#: the revision issue 53 started from
BEFORE = os.environ.get('FRF_LAYOUT_BEFORE', '91c1848')
#: core's subpackages, lowest first (.importlinter, contract core-floors)
CORE_ORDER = ('recording', 'progress', 'jsonable', 'model', 'excitation', 'estimation',
              'simulation', 'fit', 'loop', 'diagnosis')
SAME_FLOOR = {'recording', 'progress', 'jsonable'}


def modules(root: Path) -> dict[str, Path]:
    """Return {dotted module name: path} of the package under ``root``."""
    out = {}
    for p in (root / 'frf_ident').rglob('*.py'):
        parts = list(p.relative_to(root).with_suffix('').parts)
        if parts[-1] == '__init__':
            parts = parts[:-1]
        out['.'.join(parts)] = p
    return out


def imports(root: Path) -> dict[str, set[str]]:
    """Return {module: the package's modules it imports} (relative imports resolved)."""
    mods = modules(root)
    graph = {m: set() for m in mods}
    for m, p in mods.items():
        base = m.split('.') if p.name == '__init__.py' else m.split('.')[:-1]
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    anchor = base[:len(base) - node.level + 1]
                    target = '.'.join(anchor + ([node.module] if node.module else []))
                else:
                    target = node.module or ''
                for a in node.names:
                    full = f'{target}.{a.name}'
                    t = full if full in mods else target
                    if t in mods and t != m:
                        graph[m].add(t)
            elif isinstance(node, ast.Import):
                graph[m].update(a.name for a in node.names if a.name in mods and a.name != m)
    return graph


def cycles(graph: dict[str, set[str]]) -> int:
    """Return how many strongly connected components of more than one module there are."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components
    import numpy as np
    names = sorted(graph)
    index = {m: i for i, m in enumerate(names)}
    rows = [index[m] for m in names for t in graph[m]]
    cols = [index[t] for m in names for t in graph[m]]
    adj = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    _, labels = connected_components(adj, directed=True, connection='strong')
    return int(sum(np.sum(labels == k) > 1 for k in set(labels.tolist())))


def upward_arrows(graph: dict[str, set[str]]) -> list[str]:
    """Return the imports from a core subpackage to one on a higher floor."""
    def floor(m: str) -> int | None:
        parts = m.split('.')
        if len(parts) < 3 or parts[1] != 'core' or parts[2] not in CORE_ORDER:
            return None
        return 0 if parts[2] in SAME_FLOOR else CORE_ORDER.index(parts[2])
    out = []
    for m, targets in graph.items():
        for t in targets:
            a, b = floor(m), floor(t)
            if a is not None and b is not None and b > a:
                out.append(f'{m} -> {t}')
    return sorted(out)


def diagnosis_sizes(root: Path) -> tuple[int, int, int, int]:
    """Return core/diagnosis' largest module, longest function, and how many exceed 400 / 80."""
    big, long_, n_big, n_long = 0, 0, 0, 0
    for p in (root / 'frf_ident' / 'core' / 'diagnosis').rglob('*.py'):
        text = p.read_text()
        n = len(text.splitlines())
        big, n_big = max(big, n), n_big + (n > 400)
        for f in ast.walk(ast.parse(text)):
            if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
                k = f.end_lineno - f.lineno + 1
                long_, n_long = max(long_, k), n_long + (k > 80)
    return big, long_, n_big, n_long


def long_modules(root: Path, limit: int = 600) -> tuple[int, int]:
    """Return how many modules of frf_ident exceed ``limit`` lines, and the largest one's."""
    sizes = [len(p.read_text().splitlines()) for p in (root / 'frf_ident').rglob('*.py')]
    return sum(n > limit for n in sizes), max(sizes)


def dict_returning(root: Path) -> int:
    """Return how many public functions and methods are annotated to return a dict."""
    n = 0
    for p in (root / 'frf_ident').rglob('*.py'):
        for f in ast.walk(ast.parse(p.read_text())):
            if (isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                    and not f.name.startswith('_') and f.returns is not None):
                ann = ast.unparse(f.returns).replace(' ', '')
                if ann.startswith(('dict', 'Dict', 'Mapping')) and f.name != 'to_dict':
                    n += 1
    return n


def meta_keys(root: Path) -> tuple[int, int]:
    """Return the distinct keys read from a ``.meta`` mapping and the layers reading them."""
    keys, layers = set(), set()
    for p in (root / 'frf_ident').rglob('*.py'):
        for node in ast.walk(ast.parse(p.read_text())):
            key = None
            if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute)
                    and node.value.attr == 'meta' and isinstance(node.slice, ast.Constant)):
                key = node.slice.value
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                  and node.func.attr == 'get' and isinstance(node.func.value, ast.Attribute)
                  and node.func.value.attr == 'meta' and node.args
                  and isinstance(node.args[0], ast.Constant)):
                key = node.args[0].value
            if isinstance(key, str):
                keys.add(key)
                rel = p.relative_to(root / 'frf_ident').parts
                layers.add(rel[0] if rel[0] != 'core' else f'core/{rel[1]}')
    return len(keys), len(layers)


def measure(root: Path) -> dict[str, str]:
    """Return the figures of the tree under ``root``."""
    graph = imports(root)
    big, long_, n_big, n_long = diagnosis_sizes(root)
    keys, layers = meta_keys(root)
    n_long_modules, largest = long_modules(root)
    return {'import cycles': str(cycles(graph)),
            'upward arrows inside core': str(len(upward_arrows(graph))),
            'core/diagnosis: largest module, longest function [lines]': f'{big}, {long_}',
            'core/diagnosis: modules > 400 lines, functions > 80 lines': f'{n_big}, {n_long}',
            'frf_ident: modules > 600 lines, the largest [lines]': f'{n_long_modules}, {largest}',
            'public functions returning a dict': str(dict_returning(root)),
            'meta keys read, in how many layers': f'{keys} in {layers}'}


def rows() -> list[tuple[str, str, str, str]]:
    """Return the figures now beside those at :data:`BEFORE`."""
    now = measure(ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(['git', 'archive', BEFORE, 'frf_ident'], cwd=ROOT,
                                 capture_output=True, check=True).stdout
        subprocess.run(['tar', '-x', '-C', tmp], input=archive, check=True)
        before = measure(Path(tmp))
    return [(k, now[k], f'{before[k]} at {BEFORE}', '') for k in now]
