"""`frf-ident import FILE.csv|FILE.mat --map MAP.yaml --out BAG` (CONTRACT section 6)."""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.commands import subcommand
from frf_ident.errors import FrfIdentInputError


@subcommand('import', 'convert measured data (CSV or MAT table) into a bag, using a map file')
def _import_args(p: argparse.ArgumentParser) -> None:
    p.add_argument('file', type=Path, help='measured data: .csv or .mat')
    p.add_argument('--map', type=Path, required=True,
                   help='YAML map: time, joints and their columns/variables, unit scales '
                        '(see frf_ident/io/README_io.md; examples in config/map_*.yaml)')
    p.add_argument('--out', type=Path, required=True, help='bag directory to create')


def import_file(file: Path, map_path: Path, out: Path, *, progress=print) -> Path:
    """Import ``file`` with ``map_path`` and write the bag ``out`` (never overwritten)."""
    from frf_ident.bag import write_recording
    from frf_ident.core.detect import detect_excitation
    from frf_ident.errors import EstimationError
    from frf_ident.io.importer import import_table
    if out.exists():
        raise FrfIdentInputError(f'--out {str(out)!r} already exists; choose a new bag path '
                                 f'(nothing was overwritten)')
    rec = import_table(file, map_path)
    info = rec.meta['import']
    progress(f'{file.name}: {rec.t.size} samples at {rec.fs:.6g} Hz '
             f'(t = {rec.t[0]:.3f} .. {rec.t[-1]:.3f} s), joints {", ".join(rec.joint_names)}')
    for key, how in info['derived'].items():
        progress(f'  {key}: {how}')
    for j, name in enumerate(rec.joint_names):
        sig, what = (rec.reference, 'reference') if rec.reference is not None \
            and not _nan(rec.reference[:, j]) else (rec.effort, 'effort')
        try:
            progress(f'  {name} {what}: {detect_excitation(sig[:, j], rec.fs).describe()}')
        except EstimationError:
            pass
    write_recording(rec, out)
    progress(f'wrote {out}')
    return out


def _nan(x) -> bool:
    import numpy as np
    return bool(np.isnan(x).all())


def _import(args: argparse.Namespace) -> int:
    import_file(args.file, args.map, args.out)
    return 0


def _register() -> None:
    from frf_ident.cli import command
    command('import')(_import)


_register()
