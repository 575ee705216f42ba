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
"""Import measured tables (CSV or MAT) as bags, using a map file."""
from __future__ import annotations

from pathlib import Path

from frf_ident.app.outdir import check_out
from frf_ident.core.progress import Progress, sink

__all__ = ['import_file']


def import_file(file: Path, map_path: Path, out: str | Path, *,
                progress: Progress | None = None) -> Path:
    """
    Import a measured table as a bag and say what excitation each joint carries.

    Parameters
    ----------
    file
        Measured data, .csv or .mat.
    map_path
        YAML map naming the time, joints, columns and unit scales (see docs/import_maps.md).
    out
        Bag directory to create; an existing path, or one that cannot be created, is
        refused before the file is read (:func:`~frf_ident.app.outdir.check_out`).
    progress
        Called with one line per step; None: silent.

    Returns
    -------
    Path
        ``out``.

    """
    progress = sink(progress)
    from frf_ident.bag import write_recording
    from frf_ident.core.estimation.checks import check_band
    from frf_ident.core.excitation.detect import detect_excitation
    from frf_ident.core.excitation.detect_input import excitation_source
    from frf_ident.errors import EstimationError
    from frf_ident.io.importer import import_table
    out = check_out(out, outputs=None, overwrite=False)
    rec = import_table(file, map_path)
    info = rec.import_info
    progress(f'{file.name}: {rec.t.size} samples at {rec.fs:.6g} Hz '
             f'(t = {rec.t[0]:.3f} .. {rec.t[-1]:.3f} s), joints {", ".join(rec.joint_names)}')
    for key, how in info['derived'].items():
        progress(f'  {key}: {how}')
    # the signal `estimate` will detect the excitation on (one rule for both)
    sig, what = excitation_source(rec.reference, rec.effort)
    for j, name in enumerate(rec.joint_names):
        try:
            det = detect_excitation(sig[:, j], rec.fs)
        except EstimationError:
            continue
        progress(f'  {name} {what}: {det.describe()}')
        band = det.freq_hz if det.kind == 'multisine' else [det.f_low, det.f_high]
        try:
            check_band(band, rec.fs, where=f'{name} {what}')
        except EstimationError as exc:      # `estimate` refuses it: say so now
            progress(f'  warning: {exc}')
    write_recording(rec, out)
    progress(f'wrote {out}')
    return out
