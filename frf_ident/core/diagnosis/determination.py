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
Say which diagnosed values a record determines, and which experiment would determine the rest.

Both routes give every parameter of a named effect a standard error. A parameter whose
standard error exceeds NOT_DETERMINED_SHARE of its value (or, on the experiments route, whose
refits disagree beyond their errors and do not settle) is not determined by the record: its
effect carries a :class:`.records.NotDetermined` entry with the range the value may lie in and
the experiment that would pin it, and its score is 0 (it does not count as found).
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Iterator

from .common import Effect
from .records import NotDetermined, Unexplained
from .thresholds import NOT_DETERMINED_SHARE

__all__ = ['EXPERIMENT', 'labelled', 'magnitudes', 'not_determined', 'on_unexplained_axes',
           'share_text', 'undetermined_effects']

#: per parameter, the experiment that would determine it where a record did not (why: viscous
#: friction grows with speed where Coulomb friction and a backlash do not; a stiffening gear
#: shows its second stiffness only at loads beyond its breakpoint; a damping or stiffness sets
#: the resonance's width and place; a delay the phase slope at high frequencies)
EXPERIMENT = {
    'viscous_friction': 'a slower multisine or constant-velocity runs at several speeds',
    'coulomb_friction': 'constant-velocity runs at several speeds in both directions',
    'backlash': 'a multisine of smaller amplitude about zero load',
    'stiffness_k2': 'chirps at several torque amplitudes',
    'stiffness_breakpoint': 'chirps at several torque amplitudes',
    'stiffness': 'a multisine with denser lines around the resonance',
    'damping': 'a multisine with denser lines around the resonance',
    'motor_inertia': 'a multisine reaching above the resonance',
    'link_inertia': 'a multisine with lines below the antiresonance',
    'time_delay': 'a multisine reaching higher frequencies',
    'second_mode': 'a chirp or a multisine with dense lines through the mode',
    'torque_ripple': 'a slower constant-velocity run over more of the travel',
    'gravity': 'motion over a larger range of the joint angles',
    'gravity_torque': 'motion over a larger range of the joint angles'}

#: parameters that may be negative: their range is not cut at 0
_SIGNED = ('gravity_torque',)


def magnitudes(effect: Effect) -> Iterator[tuple[str, float, float | None]]:
    """
    Yield (parameter, value, standard error) of an effect's magnitudes.

    A magnitude is a scalar parameter other than 0, a term's amplitude (the terms the
    diagnosis added: those with a standard error) or a value of a mapping (a second mode's
    frequency, damping ratio and inertia: ``second_mode damping_ratio``); phases and spatial
    frequencies are not (their errors are reported, the share of a value means nothing for
    them).
    """
    se = effect.standard_error or {}
    for key, value in effect.parameters.items():
        if isinstance(value, dict):
            errs = se.get(key) or {}
            for sub, v in value.items():
                if isinstance(v, (int, float)) and v != 0:
                    yield f'{key} {sub}', float(v), errs.get(sub)
        elif isinstance(value, (list, tuple)):
            for term, err in zip(value, se.get(key) or [None] * len(value)):
                if err is not None and 'amplitude' in term:
                    yield f'{key} amplitude', float(term['amplitude']), err.get('amplitude')
        elif isinstance(value, (int, float)) and not isinstance(value, bool) and value != 0:
            yield key, float(value), se.get(key)


def share_text(value: float, se: float) -> str:
    """Return why a standard error leaves a value undetermined, as a short text."""
    if not math.isfinite(se):
        return 'the record leaves it free (no finite standard error)'
    return f'standard error {se:.3g}, {100 * se / max(abs(value), 1e-300):.0f} % of the value'


def not_determined(parameter: str, value: float, se: float, reason: str,
                   seen: list[float] = ()) -> NotDetermined:
    """
    Return the entry of a parameter the record does not determine.

    Parameters
    ----------
    parameter : str
        The model-file key ('torque_ripple amplitude' for a term's amplitude).
    value, se : float
        Its value and standard error.
    reason : str
        Why it is not determined.
    seen : list of float
        Other values its refits took.

    Returns
    -------
    NotDetermined
        With the range spanned by ``seen``, the value and value +- 2 se (not below 0 for a
        parameter that cannot be negative), and the experiment of :data:`EXPERIMENT`.

    """
    spread = 2.0 * se if math.isfinite(se) else math.inf
    vals = [v for v in [value, *seen] if math.isfinite(v)]
    lo, hi = min(vals + [value - spread]), max(vals + [value + spread])
    if parameter.split()[0] not in _SIGNED:
        lo = max(lo, 0.0)
    return NotDetermined(parameter, [lo, hi], reason,
                         EXPERIMENT.get(parameter.split()[0], 'a longer record'))


def labelled(effect: Effect, labels: list[NotDetermined]) -> Effect:
    """Return the effect with ``labels`` added (one per parameter); score 0 if it has any."""
    have = {n.parameter for n in effect.not_determined}
    new = effect.not_determined + [n for n in labels if n.parameter not in have]
    return replace(effect, not_determined=new, score=0.0 if new else effect.score)


def undetermined_effects(effects: list[Effect]) -> list[Effect]:
    """
    Return the effects with every magnitude whose standard error exceeds its share labelled.

    A magnitude with a standard error above NOT_DETERMINED_SHARE of its value (or none that
    is finite) gets a :class:`.records.NotDetermined` entry and its effect the score 0; a
    parameter without a standard error (None: not estimated) is left as it is. An effect a
    stage labelled already (a mode's damping ratio its profile leaves free,
    experiments/mode_search.py) scores 0 too.
    """
    out = []
    for e in effects:
        labels = [not_determined(k, v, float(se), share_text(v, float(se)))
                  for k, v, se in magnitudes(e)
                  if se is not None and not float(se) <= NOT_DETERMINED_SHARE * abs(v)]
        out.append(labelled(e, labels) if labels or e.not_determined else e)
    return out


def on_unexplained_axes(effects: list[Effect], unexplained: list[Unexplained]) -> list[Effect]:
    """
    Return the effects with the values on an axis left unexplained labelled not determined.

    An axis the extended model leaves clearly above its noise floor (an ``unexplained`` entry
    with its ``misfit_share``) lacks something the effects were fitted next to: a missed
    effect or a mode shifts their values by more than their standard errors say (a
    stiffening gear's breakpoint 36 % off next to a joint damping the diagnosis did not
    keep, 6.6 errors: ``python -m benchmarks.diagnosis_uncertainty 1 5804``). Values without
    a standard error (nominal terms) are left alone.
    """
    left = {u.axis: u.misfit_share for u in unexplained
            if u.misfit_share is not None and u.kind is None}
    out = []
    for e in effects:
        labels = [] if e.axis not in left else [
            not_determined(k, v, float(se), f'its axis stays unexplained ({100 * left[e.axis]:.0f}'
                                            f' % of the nominal misfit left): what the model '
                                            f'lacks there moves it beyond its error')
            for k, v, se in magnitudes(e) if se is not None]
        out.append(labelled(e, labels) if labels else e)
    return out
