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
What an MJCF holds of a model diagnosed against it: the drive terms relative to the nominal.

A model file naming an MJCF is read in our parameters (:func:`~frf_ident.io.mjcf.linear.
axis_values`); the diagnosis changes those parameters (its effects) and the MJCF must carry
the change. :func:`held_drives` turns a changed model back into each axis' MJCF drive terms,
relative to what the nominal MJCF has, by :data:`~frf_ident.io.mjcf.drive_map.MAPPING`:

- a **rigid** joint of the MJCF (no link-side hinge) has no motor/link split: our view puts an
  artificial share of its inertia on the motor side (:func:`~frf_ident.io.mjcf.drive_map.
  rigid_split`). Any change of its total inertia (motor + link) is rotor inertia the MJCF
  lacks: ``armature`` = the MJCF's + (Jm + Jo) - (Jm + Jo) of the nominal view. So the
  artificial share never appears as a finding: only the change of the total does.
- a rigid joint becomes the **series-elastic pair** (the link-side hinge with ``stiffness``
  and ``damping``) when the model's spring differs from the rigid view's and MuJoCo's time
  step integrates the resonance it makes (:data:`SPRING_MAX_STEP_ANGLE`): the diagnosis found
  a resonance the rigid MJCF lacks. ``armature`` is then the motor inertia; the link side
  keeps the MJCF's bodies.
- a joint that is elastic in the MJCF keeps its pair: ``armature`` = motor inertia less what
  the motor-side body adds.
- ``damping`` (motor side) = viscous friction, ``frictionloss`` = Coulomb friction, actuator
  ``delay`` = time delay, ``ctrlrange`` from the torque limit, exactly; a ``second_mode`` as
  the mode body and hinge (frf_ident/io/mjcf/link_mode.py).

What the MJCF cannot hold is returned as a :class:`~frf_ident.io.mjcf.drive_map.Limitation`
with what was written instead, never dropped: a link inertia or coupling that differs from the
MJCF's M(q) (its bodies are kept), a gravity that differs (the bodies' masses hold it: a
different one means wrong masses), a stiffening spring, backlash, ripple (:func:`~frf_ident.io.
mjcf.drive_map.limitations`), a spring too stiff for the time step, a total inertia below the
MJCF's rigid body. Nothing here imports mujoco.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.io.mjcf.drive_map import JointDrive, Limitation, limitations, mode_terms
import numpy as np

__all__ = ['Held', 'LINK_INERTIA_TOLERANCE', 'SPRING_MAX_STEP_ANGLE', 'held_drives']

#: a spring is written as the series-elastic pair only where MuJoCo's step integrates its
#: resonance: w_r h at most this (MuJoCo integrates joint stiffness explicitly; the
#: semi-implicit Euler step of an undamped oscillator is stable below w h = 2, and at
#: w h = 1 its frequency is 4 % off). A stiffer spring is written rigid (reported where its
#: antiresonance lies below the Nyquist frequency, i.e. where a measured FRF could show it)
SPRING_MAX_STEP_ANGLE = 1.0
#: a relative change of a rigid view's spring below this is no spring found (rounding of the
#: search's rescales)
SPRING_CHANGE = 1e-6
#: a link inertia differing from the MJCF's by more than this share is reported (the MJCF's
#: bodies are kept); 2 %: the two-mass fit's separation of motor and link inertia on a
#: multisine FRF of the iiwa (docs/mujoco.md, worked example: -0.7 and -2.1 %)
LINK_INERTIA_TOLERANCE = 0.02


@dataclass
class Held:
    """A model as MJCF drive terms: one JointDrive per axis and what the MJCF cannot hold."""

    drives: list[JointDrive]
    limitations: list[Limitation] = field(default_factory=list)

    def lines(self) -> list[str]:
        """Return one line per term the MJCF cannot hold."""
        return [str(x) for x in self.limitations]


def held_drives(robot: RobotParams, nominal: RobotParams, base: list[JointDrive],
                timestep: float) -> Held:
    """
    Return ``robot``'s drive terms as the MJCF ``nominal`` was read from holds them.

    Parameters
    ----------
    robot : RobotParams
        The model to write (the nominal view with diagnosed changes).
    nominal : RobotParams
        The nominal MJCF read in our parameters (the same axes).
    base : list of JointDrive
        The nominal MJCF's own drive terms per axis (``stiffness`` None: a rigid joint).
    timestep : float
        MuJoCo's time step [s] the model is simulated with.

    Returns
    -------
    Held
        The drive terms per axis and the limitations.

    """
    drives, lims = [], []
    for a, a0, d0 in zip(robot.axes, nominal.axes, base):
        d, more = _axis(a, a0, d0, timestep, robot.sample_rate)
        drives.append(d)
        lims += more + limitations(a) + _gravity(a, a0)
    lims += _coupling(robot, nominal)
    return Held(drives, lims)


def _axis(a: AxisParams, a0: AxisParams, d0: JointDrive, h: float, fs: float
          ) -> tuple[JointDrive, list[Limitation]]:
    """One axis: rigid or elastic, the inertias relative to the nominal view."""
    lims: list[Limitation] = []
    common = {'damping': float(a.viscous_friction), 'frictionloss': float(a.coulomb_friction),
              'torque_limit': float(a.torque_limit), 'delay': float(a.time_delay),
              **mode_terms(a)}
    spring = not d0.elastic and abs(a.stiffness / a0.stiffness - 1.0) > SPRING_CHANGE
    w_r = math.sqrt(a.stiffness * (1.0 / a.motor_inertia + 1.0 / a.link_inertia))
    if spring and w_r * h > SPRING_MAX_STEP_ANGLE:
        spring = False
        f_a = math.sqrt(a.stiffness / a.link_inertia) / (2 * math.pi)
        if f_a < fs / 2:
            lims.append(Limitation(a.name, 'stiffness', f'{a.stiffness:g} N m/rad (resonance '
                                   f'{w_r / (2 * math.pi):.4g} Hz)', f'written: rigid; the time '
                                   f'step {h:g} s cannot integrate it (w h > '
                                   f'{SPRING_MAX_STEP_ANGLE:g}): lower the MJCF timestep'))
    if d0.elastic or spring:
        # the motor-side body of the MJCF's own pair adds its (tiny) inertia to the view's Jm
        body = a0.motor_inertia - d0.armature if d0.elastic else 0.0
        mjcf_link = a0.link_inertia if d0.elastic else \
            a0.motor_inertia + a0.link_inertia - d0.armature
        arm = a.motor_inertia - body
        if abs(a.link_inertia / mjcf_link - 1.0) > LINK_INERTIA_TOLERANCE:
            lims.append(Limitation(a.name, 'link_inertia', f'{a.link_inertia:.4g} kg m^2',
                                   f"written: the MJCF's bodies, {mjcf_link:.4g} kg m^2 at the "
                                   f'pose ({100 * (a.link_inertia / mjcf_link - 1):+.1f} %): '
                                   f'its masses or inertias would change'))
        return JointDrive(a.name, armature=max(arm, 0.0), stiffness=float(a.stiffness),
                          link_damping=float(a.damping), **common), lims
    total, total0 = a.motor_inertia + a.link_inertia, a0.motor_inertia + a0.link_inertia
    arm = d0.armature + total - total0
    if arm < 0:
        lims.append(Limitation(a.name, 'motor_inertia', f'total inertia {total:.4g} kg m^2',
                               f"written: armature 0; the MJCF's rigid body alone has "
                               f'{total0 - d0.armature:.4g} kg m^2: its masses are too large'))
    if abs(a.damping - a0.damping) > 1e-12 * max(abs(a0.damping), 1.0):
        lims.append(Limitation(a.name, 'damping', f'{a.damping:g} N m s/rad (transmission)',
                               'written: none (a rigid joint has no transmission to damp)'))
    return JointDrive(a.name, armature=max(arm, 0.0), stiffness=None, link_damping=0.0,
                      **common), lims


def _gravity(a: AxisParams, a0: AxisParams) -> list[Limitation]:
    """Return a gravity that differs from the MJCF's: not written (its bodies hold it)."""
    same = a.gravity_torque == a0.gravity_torque and a.gravity == a0.gravity
    if same:
        return []
    return [Limitation(a.name, 'gravity', f'load {a.gravity_torque:g} N m and '
                       f'{len(a.gravity)} term(s), the MJCF {a0.gravity_torque:g} N m and '
                       f'{len(a0.gravity)}', "written: the MJCF's bodies; a different gravity "
                       'means wrong masses or centres of mass there')]


def _coupling(robot: RobotParams, nominal: RobotParams) -> list[Limitation]:
    """Return a link coupling that differs from the MJCF's M(q): not written."""
    c = robot.link_inertia_matrix() - np.diag(np.diag(robot.link_inertia_matrix()))
    c0 = nominal.link_inertia_matrix() - np.diag(np.diag(nominal.link_inertia_matrix()))
    diff = np.abs(c - c0).max() if c.size else 0.0
    if diff <= LINK_INERTIA_TOLERANCE * max(np.abs(c0).max(), 1e-300):
        return []
    return [Limitation('link_coupling', 'link_coupling', f'up to {diff:.4g} kg m^2 from the '
                       "MJCF's", "written: the MJCF's bodies (M(q) at the pose)")]
