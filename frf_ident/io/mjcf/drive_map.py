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
The one mapping between our drive parameters and MJCF attributes, both directions.

Our parameters are :class:`~frf_ident.core.model.params.AxisParams`; docs/mujoco.md prints
:data:`MAPPING` as its table.

A flexible joint is two hinges in series on the same axis: the actuated motor-side hinge keeps
the joint's name and carries the rotor (``armature``), its viscous friction (``damping``) and
dry friction (``frictionloss``); a child body holds the link-side hinge ``<joint>`` +
:data:`LINK_SUFFIX` with ``stiffness`` and ``damping`` on the relative angle (the spring of
eqs. 1-2). A joint without that child hinge is rigid. An axis' ``second_mode`` is a further
child body of the link body, holding the hinge ``<joint>`` + :data:`MODE_SUFFIX` on the same
axis with the mode's inertia, ``stiffness`` and ``damping`` (frf_ident/io/mjcf/link_mode.py).
The actuator is a torque motor on the motor-side hinge: our command u [N m] is
``gear * ctrl``, the torque MuJoCo applies ``gainprm[0] * u`` (1 for a ``motor``: the torque
constant's ratio to its nominal value), the limit ``gear * ctrlrange``.

Nothing here imports mujoco: these are names, numbers and the limits of the mapping.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.model.params import AxisParams

__all__ = ['JointDrive', 'LINK_SUFFIX', 'Limitation', 'MAPPING', 'MODE_BODY_MASS',
           'MODE_SUFFIX', 'MOTOR_BODY_INERTIA', 'MOTOR_BODY_MASS', 'RIGID_ANTIRESONANCE_NYQUIST',
           'RIGID_MOTOR_SHARE',
           'drive_from_axis', 'limitations', 'mapping_table', 'mode_terms', 'rigid_split']

#: name of the link-side hinge of a series-elastic joint: ``<joint name>`` + this
LINK_SUFFIX = '_link'
#: name of the hinge of an axis' second, link-side mode: ``<joint name>`` + this (its body:
#: ``<joint name>`` + this + ``_body``)
MODE_SUFFIX = '_mode'

#: mass [kg] and principal inertia [kg m^2] of the body between the two hinges: MuJoCo refuses a
#: moving body without mass (``mjMINVAL``), so the motor-side body gets this much; the rotor is
#: the hinge's ``armature``. 1e-6 kg at 0.3 m adds 1e-7 kg m^2 to a parent axis: nothing a
#: measured FRF can see (the smallest armature of a real drive is ~1e-3 kg m^2 at the joint)
MOTOR_BODY_MASS = 1e-6
MOTOR_BODY_INERTIA = 1e-9
#: mass [kg] of the body of a second mode (on the hinge axis: its inertia, not its mass, is the
#: mode); taken from the link body, so the arm's mass and centre of mass stay the MJCF's
MODE_BODY_MASS = 1e-6

#: our parameters of a rigid MJCF joint (no link-side hinge), an approximation: the two-mass
#: model needs a spring and a motor inertia, so the joint gets a spring whose antiresonance lies
#: this many Nyquist frequencies up (its effect below Nyquist < (1/20)^2 = 0.25 %, 0.02 dB) ...
RIGID_ANTIRESONANCE_NYQUIST = 20.0
#: ... and, without an ``armature``, this share of its inertia on the motor side (the total kept)
RIGID_MOTOR_SHARE = 0.01


@dataclass(frozen=True)
class Row:
    """
    One row of :data:`MAPPING`: our key, the MJCF attribute, unit, how exact, the diagnosis.

    ``diagnosis``: which effect of ``diagnose`` against an MJCF sets it and what is written
    (frf_ident/io/mjcf/held.py, docs/mujoco.md "Diagnosis against an MJCF").
    """

    ours: str
    mjcf: str
    unit: str
    note: str
    diagnosis: str = '-'


#: our parameter -> MJCF attribute (docs/mujoco.md prints this table)
MAPPING: tuple[Row, ...] = (
    Row('motor_inertia', 'motor-side `joint@armature`', 'kg m^2',
        'exact (rotor inertia through the gear; MuJoCo ignores its gyroscopic coupling, as '
        'we do)',
        '`parameter_mismatch` motor_inertia -> `armature`; on a rigid joint the change of '
        "its total inertia (the view's 1 % motor share is never reported)"),
    Row('link_inertia, link_coupling', "the bodies' `inertial` (M(q) of the link side)",
        'kg m^2', 'MJCF -> ours: M(q) at the pose; ours -> MJCF: kept from the MJCF '
        '(a standalone export puts link_inertia on one body per axis, no coupling)',
        '`parameter_mismatch` link_inertia on a rigid joint -> `armature` (the total); on '
        "an elastic one not written, reported (the MJCF's bodies kept)"),
    Row('stiffness', f'link-side `joint@stiffness` (hinge `<joint>{LINK_SUFFIX}`)', 'N m/rad',
        'exact: spring on the relative angle, springref 0',
        '`parameter_mismatch` stiffness on a rigid joint with a resonance in the band '
        '(stage 0b) -> the series-elastic pair inserted; a spring too stiff for the time '
        'step: written rigid, reported'),
    Row('damping', f'link-side `joint@damping` (hinge `<joint>{LINK_SUFFIX}`)', 'N m s/rad',
        'exact: acts on the relative velocity',
        '`parameter_mismatch` damping -> link-side `damping` (elastic joints)'),
    Row('viscous_friction', 'motor-side `joint@damping`', 'N m s/rad', 'exact',
        '`viscous_friction` -> motor-side `damping`'),
    Row('coulomb_friction', 'motor-side `joint@frictionloss`', 'N m',
        'approximate: a soft constraint (solref/solimp), not a set-valued or tanh law: a '
        'stuck joint creeps, see docs/mujoco.md',
        '`coulomb_friction` -> `frictionloss` (simulated so: candidates run in MuJoCo)'),
    Row('torque_limit', '`actuator@ctrlrange` x `gear` (`forcerange` if set)', 'N m', 'exact',
        '- (kept)'),
    Row('(torque constant)', '`general` actuator `gainprm[0]` (1 for `motor`)', '1',
        'exact: applied torque = gainprm[0] x command',
        '- (not in the vocabulary; kept)'),
    Row('time_delay', '`actuator@delay` (ctrl history, `nsample` >= delay / timestep + 1)',
        's', 'whole time steps exact; a fraction of a step interpolated (`interp` linear)',
        '`time_delay` -> `actuator@delay`'),
    Row('gravity_torque, gravity', "the bodies' masses and `option@gravity`", 'N m',
        'MJCF -> ours: g(q) at the pose and its gradient; ours -> MJCF: not written (the '
        "MJCF's rigid body holds it)",
        '`gravity`: not simulated, listed in `rejected` (a different gravity means wrong '
        'masses)'),
    Row('stiffness_k2, stiffness_breakpoint', '(link-side `joint@stiffness` polynomial)',
        'N m/rad, rad', 'not representable as a breakpoint; MuJoCo 4 takes stiffness="k1 c2 c3" '
        '(torque k1 d + c2 d^2 + c3 d^3), the closest is a cubic; written: the linear k1',
        '`stiffness_nonlinearity`: not simulated, listed in `rejected`'),
    Row('backlash', '-', 'rad', 'not representable (no dead zone on a joint spring)',
        '`backlash`: not simulated, listed in `rejected`'),
    Row('torque_ripple', '-', 'N m', 'not representable (no position-periodic joint torque)',
        '`torque_ripple`: not simulated, listed in `rejected`'),
    Row('second_mode', f'child body of the link body: inertia J_e about hinge '
        f'`<joint>{MODE_SUFFIX}` (same axis), its `stiffness` J_e (2 pi f)^2 and `damping` '
        '2 zeta J_e 2 pi f', 'Hz, -, kg m^2',
        'exact: J_e taken from the link body (standalone: link_inertia - J_e; an MJCF base: '
        "its link body's inertial less the mode's, where that stays a valid inertia, else "
        'kept and reported: the low-frequency inertia +J_e)',
        '`second_mode` -> the mode body and hinge (simulated so)'),
    Row('encoder_resolution, velocity_noise, torque_noise', '-', '',
        'measurement, not the MJCF: the model file keeps them, the plant applies them',
        "- (the record's)"),
)


def mapping_table() -> str:
    """
    Return :data:`MAPPING` as the Markdown table docs/mujoco.md shows.

    Returns
    -------
    str
        Header and one row per entry.

    Examples
    --------
    >>> print(mapping_table().splitlines()[0])
    | ours | MJCF | unit | how exact | diagnosis against an MJCF |

    """
    lines = ['| ours | MJCF | unit | how exact | diagnosis against an MJCF |',
             '|---|---|---|---|---|']
    lines += [f'| `{r.ours}` | {r.mjcf} | {r.unit} | {r.note} | {r.diagnosis} |'
              for r in MAPPING]
    return '\n'.join(lines)


@dataclass(frozen=True)
class JointDrive:
    """
    The drive terms of one joint in MJCF attributes (SI units).

    Parameters
    ----------
    joint : str
        The actuated (motor-side) joint's name.
    armature : float
        Motor-side ``armature`` [kg m^2].
    damping : float
        Motor-side ``damping`` [N m s/rad].
    frictionloss : float
        Motor-side ``frictionloss`` [N m].
    stiffness : float or None
        Link-side hinge ``stiffness`` [N m/rad]; None: a rigid joint (no link-side hinge).
    link_damping : float
        Link-side hinge ``damping`` [N m s/rad].
    torque_limit : float
        ``gear * ctrlrange`` [N m].
    delay : float
        Actuator ``delay`` [s].
    mode_inertia : float
        Inertia [kg m^2] of the second mode's body about its hinge; 0: no second mode.
    mode_stiffness : float
        ``stiffness`` [N m/rad] of the second mode's hinge.
    mode_damping : float
        ``damping`` [N m s/rad] of the second mode's hinge.

    """

    joint: str
    armature: float
    damping: float
    frictionloss: float
    stiffness: float | None
    link_damping: float
    torque_limit: float
    delay: float = 0.0
    mode_inertia: float = 0.0
    mode_stiffness: float = 0.0
    mode_damping: float = 0.0

    @property
    def has_mode(self) -> bool:
        """Tell whether the joint carries a second, link-side mode."""
        return self.mode_inertia > 0

    @property
    def mode_joint(self) -> str:
        """Return the name of the second mode's hinge."""
        return self.joint + MODE_SUFFIX

    @property
    def elastic(self) -> bool:
        """Tell whether the joint has the series-elastic hinge pair."""
        return self.stiffness is not None

    @property
    def link_joint(self) -> str:
        """Return the name of the link-side hinge."""
        return self.joint + LINK_SUFFIX


@dataclass(frozen=True)
class Limitation:
    """A term of ours MJCF cannot hold: the axis, our key, its value, the closest MJCF."""

    axis: str
    key: str
    value: str
    closest: str

    def __str__(self) -> str:
        """Return one line: what is not representable and what was written instead."""
        return f'{self.axis}: {self.key} = {self.value} not representable in MJCF; {self.closest}'


def drive_from_axis(axis: AxisParams, *, elastic: bool = True) -> JointDrive:
    """
    Return the MJCF drive terms of one of our axes (ours -> MJCF).

    Parameters
    ----------
    axis : AxisParams
        The axis.
    elastic : bool, optional
        Write the series-elastic hinge pair (default); False: a rigid joint (motor inertia as
        armature, no spring, the transmission damping dropped).

    Returns
    -------
    JointDrive
        The attributes; what they cannot hold is in :func:`limitations`.

    """
    return JointDrive(joint=axis.name, armature=float(axis.motor_inertia),
                      damping=float(axis.viscous_friction),
                      frictionloss=float(axis.coulomb_friction),
                      stiffness=float(axis.stiffness) if elastic else None,
                      link_damping=float(axis.damping) if elastic else 0.0,
                      torque_limit=float(axis.torque_limit), delay=float(axis.time_delay),
                      **mode_terms(axis))


def mode_terms(axis: AxisParams) -> dict[str, float]:
    """
    Return the :class:`JointDrive` fields of ``axis``' second mode (empty without one).

    Examples
    --------
    >>> a = AxisParams(link_inertia=2.0, second_mode={'frequency_hz': 50.0,
    ...                'damping_ratio': 0.0, 'inertia': 0.5})
    >>> round(mode_terms(a)['mode_stiffness'])
    49348

    """
    terms = axis.second_mode_terms()
    if terms is None:
        return {}
    return dict(zip(('mode_inertia', 'mode_stiffness', 'mode_damping'), terms))


def limitations(axis: AxisParams) -> list[Limitation]:
    """
    Return the terms of ``axis`` that MJCF cannot hold, with the closest approximation.

    Parameters
    ----------
    axis : AxisParams
        The axis.

    Returns
    -------
    list of Limitation
        Empty when every term maps (see :data:`MAPPING`).

    """
    out = []
    if axis.stiffness_k2 is not None and axis.stiffness_k2 != axis.stiffness:
        out.append(Limitation(axis.name, 'stiffness_k2', f'{axis.stiffness_k2:g} N m/rad beyond '
                              f'{axis.stiffness_breakpoint:g} rad',
                              f'written: the linear stiffness {axis.stiffness:g} N m/rad'))
    if axis.backlash > 0:
        out.append(Limitation(axis.name, 'backlash', f'{axis.backlash:g} rad',
                              'written: none (a spring without dead zone)'))
    if axis.torque_ripple:
        amp = max(abs(float(r['amplitude'])) for r in axis.torque_ripple)
        out.append(Limitation(axis.name, 'torque_ripple', f'{len(axis.torque_ripple)} term(s) up '
                              f'to {amp:g} N m', 'written: none'))
    return out


def rigid_split(inertia: float, armature: float, fs: float) -> tuple[float, float, float]:
    """
    Return (motor_inertia, link_inertia, stiffness) of our view of a rigid MJCF joint.

    The approximation of :data:`RIGID_ANTIRESONANCE_NYQUIST` and :data:`RIGID_MOTOR_SHARE`.

    Parameters
    ----------
    inertia : float
        The joint's link-side inertia M_ii [kg m^2] (without the armature).
    armature : float
        Its ``armature`` [kg m^2].
    fs : float
        Sample rate [Hz].

    Returns
    -------
    tuple of float
        Motor inertia, link inertia [kg m^2] and spring stiffness [N m/rad].

    """
    if armature > 0:
        jm, jo = armature, inertia
    else:
        jm, jo = RIGID_MOTOR_SHARE * inertia, (1.0 - RIGID_MOTOR_SHARE) * inertia
    w = 2.0 * math.pi * RIGID_ANTIRESONANCE_NYQUIST * fs / 2.0
    return jm, jo, jo * w * w
