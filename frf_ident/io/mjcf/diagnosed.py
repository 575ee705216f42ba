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
The diagnosis against an MJCF written back as MJCF, and its gain measured by MuJoCo.

:func:`write_extended` writes ``extended_model.xml`` (the nominal MJCF with the diagnosed drive
terms, :meth:`~frf_ident.io.mjcf.candidate.MjcfModels.write`), lists per axis the MJCF
attributes before and after, what the MJCF cannot hold, and measures the gain by simulating
the two files themselves in MuJoCo (each read back from disk, the record's experiments driven
through the record's controller, the held-out part estimated like the measurement): held-out
FRF error and time NRMSE, nominal MJCF vs extended MJCF (report.json ``mjcf``,
docs/CONTRACT.md §7).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from frf_ident.core.diagnosis.pipeline import Diagnosis
from frf_ident.core.diagnosis.records import Scores
from frf_ident.core.model.params import MjcfSource
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.io.mjcf.candidate import MjcfModels, read_drives, simulate_robot
from frf_ident.io.mjcf.drive_map import JointDrive
from frf_ident.io.mjcf.robot import load_robot

__all__ = ['AxisTerms', 'MjcfResult', 'write_extended']

#: the file the extended MJCF is written to, beside report.json
EXTENDED_XML = 'extended_model.xml'
#: the JointDrive attributes reported, with the MJCF element each is
TERMS = {'armature': 'joint@armature', 'damping': 'joint@damping',
         'frictionloss': 'joint@frictionloss', 'stiffness': '<joint>_link@stiffness',
         'link_damping': '<joint>_link@damping', 'delay': 'actuator@delay',
         'torque_limit': 'actuator@ctrlrange x gear',
         'mode_inertia': '<joint>_mode_body inertia about the hinge (0: no second mode)',
         'mode_stiffness': '<joint>_mode@stiffness', 'mode_damping': '<joint>_mode@damping'}


@dataclass(frozen=True)
class AxisTerms:
    """One axis' MJCF drive terms in the nominal MJCF and in extended_model.xml."""

    axis: str
    nominal: JointDrive
    extended: JointDrive

    def changed(self) -> dict[str, tuple[Any, Any]]:
        """Return the attributes that differ: name -> (nominal, extended)."""
        a, b = asdict(self.nominal), asdict(self.extended)
        return {k: (a[k], b[k]) for k in TERMS if a[k] != b[k]}

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry: the terms of both files (SI units) and what changed."""
        a, b = asdict(self.nominal), asdict(self.extended)
        return {'nominal': {k: a[k] for k in TERMS}, 'extended': {k: b[k] for k in TERMS},
                'changed': sorted(self.changed())}


@dataclass
class MjcfResult:
    """What ``diagnose`` wrote as MJCF and what MuJoCo measured of it (report ``mjcf``)."""

    file: str
    base: str
    axes: list[AxisTerms]
    #: one line per term the MJCF cannot hold, with what was written instead
    not_representable: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: held-out metrics of both files simulated by MuJoCo (None: the record has no
    #: experiments to simulate)
    nominal: Scores | None = None
    extended: Scores | None = None
    validation: str = ''

    def to_dict(self) -> dict[str, Any]:
        """Return report.json's ``mjcf`` entry."""
        return {'file': self.file, 'base': self.base,
                'axes': {t.axis: t.to_dict() for t in self.axes},
                'not_representable': list(self.not_representable), 'notes': list(self.notes),
                'held_out': None if self.nominal is None else {
                    'nominal': self.nominal.to_dict(), 'extended': self.extended.to_dict(),
                    'simulated_by': 'MuJoCo, each file read back', 'validation':
                        self.validation}}

    def lines(self) -> list[str]:
        """Return the console lines: the terms written, the limitations, the gain."""
        out = []
        for t in self.axes:
            ch = t.changed()
            if ch:
                out.append(f'{self.file}: {t.axis}: ' + ', '.join(
                    f'{k} {_num(a)} -> {_num(b)}' for k, (a, b) in ch.items()))
        out += [f'{self.file}: {x}' for x in self.not_representable + self.notes]
        if self.nominal is not None:
            out.append(f'{self.file} simulated by MuJoCo, held out: nominal MJCF FRF '
                       f'{self.nominal.frf_error_db:.3g} dB, time NRMSE '
                       f'{self.nominal.time_nrmse:.3g} -> extended MJCF FRF '
                       f'{self.extended.frf_error_db:.3g} dB, time NRMSE '
                       f'{self.extended.time_nrmse:.3g}')
        return out


def _num(x: Any) -> str:
    return 'rigid' if x is None else f'{x:.4g}'


def write_extended(models: MjcfModels, diag: Diagnosis, ctrl: PIVelocity, out: Path
                   ) -> MjcfResult:
    """
    Write extended_model.xml of a diagnosis against an MJCF; measure its gain in MuJoCo.

    Parameters
    ----------
    models : MjcfModels
        The nominal MJCF (the diagnosis' simulator).
    diag : Diagnosis
        The diagnosis (its extended model is written).
    ctrl : PIVelocity
        The controller the record ran through.
    out : Path
        The output folder.

    Returns
    -------
    MjcfResult

    """
    res = diag.result
    exp = models.write(res.extended, out / EXTENDED_XML)
    src = models.source
    names = models.nominal.joint_names
    written = load_robot(MjcfSource(str(exp.path), src.keyframe, src.pose), names)
    base = load_robot(src, names)
    axes = [AxisTerms(n, a, b)
            for n, a, b in zip(names, read_drives(base), read_drives(written))]
    result = MjcfResult(EXTENDED_XML, src.file, axes, [str(x) for x in exp.limitations],
                        list(exp.notes))
    ev = getattr(res.detail, 'evaluator', None)
    if ev is not None:
        rec = ev.rec
        result.nominal = ev.metrics(models.nominal, simulate_robot(base, rec, ctrl))
        result.extended = ev.metrics(res.extended, simulate_robot(written, rec, ctrl))
        result.validation = ev.validation_text
    else:
        result.notes.append('held-out gain not simulated: the record holds no identification '
                            'experiments (the time-series route predicts torque from motion)')
    return result
