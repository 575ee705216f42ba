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
Typed parameters of a flexible-joint robot.

Typed parameters of a flexible-joint robot: one :class:`AxisParams` per joint and the
:class:`RobotParams` of the whole arm (Saupe & Knoblach 2015, eqs. 1, 2, 20-22).

The model file (docs/CONTRACT.md, "Model file") is converted to and from these classes by
:mod:`frf_ident.core.model.schema`; the simulation reads them in
:mod:`frf_ident.core.simulation.plant`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any

from frf_ident.errors import ModelFileError
import numpy as np

__all__ = ['AxisParams', 'MjcfSource', 'RobotParams', 'SECOND_MODE_KEYS', 'UrdfSource']

#: the keys of an axis' ``second_mode`` (docs/model_file.md), in the order they are written
SECOND_MODE_KEYS = ('frequency_hz', 'damping_ratio', 'inertia')


@dataclass
class AxisParams:
    """
    Parameters of one flexible joint; keys and units of the model file (docs/CONTRACT.md §5).

    Extensions beyond the contract (documented in docs/model_file.md): ``gravity_torque``
    [N m] constant link-side load, ``gravity`` configuration-dependent link-side load (a list of
    terms ``{amplitude: G [N m], phase: phi [rad], joints: [names]}``, each adding
    ``G sin(sum of the named joints' link positions + phi)``; ``joints`` defaults to the axis
    itself, several names give the coupled-arm case, e.g. ``G sin(q2 + q3 + phi)``),
    ``encoder_resolution`` [rad/count] (0 = ideal), ``velocity_noise`` [rad/s] and
    ``torque_noise`` [N m] standard deviations of additive measurement noise, and
    ``second_mode``, a link-side mass on a spring (see below).

    Parameters
    ----------
    name : str, optional
        Joint name.
    motor_inertia : float, optional
        Motor inertia Jm [kg m^2] (> 0).
    link_inertia : float, optional
        Link inertia Jo [kg m^2] (> 0).
    stiffness : float, optional
        Transmission stiffness k1 [N m/rad] (> 0).
    damping : float, optional
        Transmission damping d [N m s/rad] (>= 0).
    viscous_friction : float, optional
        Motor-side viscous friction [N m s/rad] (>= 0).
    coulomb_friction : float, optional
        Coulomb friction Fc [N m] (>= 0).
    stiffness_k2 : float or None, optional
        Stiffness k2 [N m/rad] beyond the breakpoint; None (default): linear spring.
    stiffness_breakpoint : float or None, optional
        Breakpoint bs [rad] (> 0) of the stiffness; set together with ``stiffness_k2``.
    backlash : float, optional
        Total backlash gap [rad] (>= 0).
    torque_ripple : list of dict, optional
        Ripple terms {amplitude [N m], spatial_frequency [1/rad], phase [rad]}, each adding
        amplitude sin(spatial_frequency q_m + phase).
    time_delay : float, optional
        Input delay [s] (>= 0).
    torque_limit : float, optional
        Torque limit [N m] (> 0).
    gravity_torque : float, optional
        Constant link-side load [N m].
    gravity : list of dict, optional
        Configuration-dependent link-side load terms (see above).
    encoder_resolution : float, optional
        Encoder resolution [rad/count]; 0: ideal position measurement.
    velocity_noise : float, optional
        Standard deviation [rad/s] of the additive velocity measurement noise.
    torque_noise : float, optional
        Standard deviation [N m] of the additive torque measurement noise.
    second_mode : dict or None, optional
        A share of the link's inertia that sits on a spring behind the link (a tool, a cable
        carrier, a second gear stage): ``{frequency_hz: f [Hz], damping_ratio: zeta [-],
        inertia: J_e [kg m^2]}``. ``J_e`` is part of ``link_inertia`` (0 < J_e <
        link_inertia; the rigid link keeps the rest, so at low frequency the link weighs
        ``link_inertia``), tuned to ``f`` with the link held (stiffness J_e (2 pi f)^2) and
        damped at ``zeta`` of critical. None (default): no such mode.
    urdf_inertia : float, optional
        Share [-] of the link-side inertia and Coriolis torque of the robot's URDF (the model
        file's ``urdf``, at the URDF's own inertial parameters, divided by the gear ratio of
        its ``transmission``) that this axis carries besides its own terms: a load inertia
        that changes with the pose (an arm's reach on its base axis). Evaluated in inverse
        dynamics only; a model with it is not simulated. 0 (default): none.
    urdf_gravity : float, optional
        Share [-] of the URDF's gravity torque (over the gear ratio) this axis carries, either
        sign (a counterbalance can outweigh the link); inverse dynamics only, like
        ``urdf_inertia``. 0 (default): none.

    Raises
    ------
    ModelFileError
        A value is out of range, only one of ``stiffness_k2`` and ``stiffness_breakpoint`` is
        set, or a ripple or gravity term is malformed.

    """

    name: str = 'joint_1'
    motor_inertia: float = 35.0
    link_inertia: float = 150.0
    stiffness: float = 1.5e5
    damping: float = 400.0
    viscous_friction: float = 0.0
    coulomb_friction: float = 0.0
    stiffness_k2: float | None = None
    stiffness_breakpoint: float | None = None
    backlash: float = 0.0
    torque_ripple: list[dict[str, float]] = field(default_factory=list)
    time_delay: float = 0.0
    torque_limit: float = 150.0
    gravity_torque: float = 0.0
    gravity: list[dict[str, Any]] = field(default_factory=list)
    encoder_resolution: float = 0.0
    velocity_noise: float = 0.0
    torque_noise: float = 0.0
    second_mode: dict[str, float] | None = None
    urdf_inertia: float = 0.0
    urdf_gravity: float = 0.0

    def __post_init__(self) -> None:
        for key in ('motor_inertia', 'link_inertia', 'stiffness'):
            val = getattr(self, key)
            if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
                raise ModelFileError(f'axis {self.name}: {key}={val!r} must be positive')
        for key in ('damping', 'viscous_friction', 'coulomb_friction', 'backlash', 'time_delay',
                    'encoder_resolution', 'velocity_noise', 'torque_noise', 'urdf_inertia'):
            val = getattr(self, key)
            if not (isinstance(val, (int, float)) and math.isfinite(val) and val >= 0):
                raise ModelFileError(f'axis {self.name}: {key}={val!r} must be >= 0')
        if not (self.torque_limit > 0):
            raise ModelFileError(f'axis {self.name}: torque_limit={self.torque_limit!r} '
                                 f'must be positive')
        if (self.stiffness_k2 is None) != (self.stiffness_breakpoint is None):
            raise ModelFileError(f'axis {self.name}: stiffness_k2 and stiffness_breakpoint '
                                 f'must both be set or both be null')
        if self.stiffness_breakpoint is not None and not self.stiffness_breakpoint > 0:
            raise ModelFileError(f'axis {self.name}: stiffness_breakpoint='
                                 f'{self.stiffness_breakpoint!r} must be positive')
        for i, rip in enumerate(self.torque_ripple):
            missing = {'amplitude', 'spatial_frequency'} - set(rip)
            if missing:
                raise ModelFileError(f'axis {self.name}: torque_ripple[{i}] lacks '
                                     f'{sorted(missing)}')

        for i, g in enumerate(self.gravity):
            if not isinstance(g, dict) or 'amplitude' not in g:
                raise ModelFileError(f'axis {self.name}: gravity[{i}] must be a mapping with '
                                     f'amplitude [N m], optional phase [rad] and joints '
                                     f'[names], got {g!r}')
            unknown = set(g) - {'amplitude', 'phase', 'joints'}
            if unknown:
                raise ModelFileError(f'axis {self.name}: gravity[{i}] has unknown key(s) '
                                     f'{sorted(unknown)}; expected amplitude, phase, joints')
        if not (isinstance(self.urdf_gravity, (int, float)) and math.isfinite(self.urdf_gravity)):
            raise ModelFileError(f'axis {self.name}: urdf_gravity={self.urdf_gravity!r} must be '
                                 f'a finite number')
        if self.second_mode is not None:
            self._check_second_mode()

    def _check_second_mode(self) -> None:
        """Refuse a second mode that is not {frequency_hz > 0, damping_ratio >= 0, inertia}."""
        m = self.second_mode
        where = f'axis {self.name}: second_mode'
        if not isinstance(m, dict) or set(m) != set(SECOND_MODE_KEYS):
            raise ModelFileError(f'{where} must be a mapping with exactly '
                                 f'{", ".join(SECOND_MODE_KEYS)}, got {m!r}')
        for key in SECOND_MODE_KEYS:
            val = m[key]
            if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(
                    val):
                raise ModelFileError(f'{where}.{key}={val!r} must be a finite number')
        if not m['frequency_hz'] > 0:
            raise ModelFileError(f'{where}.frequency_hz={m["frequency_hz"]!r} must be positive')
        if not m['damping_ratio'] >= 0:
            raise ModelFileError(f'{where}.damping_ratio={m["damping_ratio"]!r} must be >= 0')
        if not 0 < m['inertia'] < self.link_inertia:
            raise ModelFileError(f'{where}.inertia={m["inertia"]!r} must be positive and below '
                                 f'link_inertia={self.link_inertia!r} (it is part of the link)')

    def second_mode_terms(self) -> tuple[float, float, float] | None:
        """
        Return the second mode's inertia [kg m^2], stiffness [N m/rad] and damping [N m s/rad].

        None without a second mode. Stiffness J_e (2 pi f)^2, damping 2 zeta J_e 2 pi f.
        """
        m = self.second_mode
        if m is None:
            return None
        w = 2 * math.pi * float(m['frequency_hz'])
        je = float(m['inertia'])
        return je, je * w * w, 2 * float(m['damping_ratio']) * je * w

    @property
    def is_linear(self) -> bool:
        return (self.coulomb_friction == 0 and self.backlash == 0 and not self.torque_ripple
                and not self.gravity and not self.urdf_inertia and not self.urdf_gravity
                and (self.stiffness_k2 is None or self.stiffness_k2 == self.stiffness))

    def gravity_joints(self, names: list[str], k: int) -> list[int]:
        """
        Axis indices whose link positions are summed in gravity term ``k``.

        Parameters
        ----------
        names : list of str
            Joint names of the robot's axes, in axis order.
        k : int
            Index of the term in ``gravity``.

        Returns
        -------
        list of int
            Indices into ``names`` of the term's ``joints`` (default: this axis).

        Raises
        ------
        ModelFileError
            The term names a joint that is not one of ``names``.

        """
        sel = self.gravity[k].get('joints') or [self.name]
        out = []
        for j in sel:
            if j not in names:
                raise ModelFileError(f'axis {self.name}: gravity[{k}].joints names {j!r}, '
                                     f'which is not one of the axes {names}')
            out.append(names.index(j))
        return out


@dataclass(frozen=True)
class MjcfSource:
    """
    The MJCF (MuJoCo model) a model file names as its rigid body (docs/model_file.md).

    Plain data: the adapter :mod:`frf_ident.io.mjcf` reads the file; the parameters of a
    :class:`RobotParams` with an ``mjcf`` are the MJCF linearised at ``pose`` in our terms.

    Parameters
    ----------
    file : str
        Path of the MJCF (absolute once loaded).
    keyframe : str or None
        Keyframe whose ``qpos`` is the start pose; None: the file's first keyframe, else its
        reference pose ``qpos0``.
    pose : dict of str to float
        Joint name -> position [rad], applied over the keyframe.

    """

    file: str
    keyframe: str | None = None
    pose: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class UrdfSource:
    """
    The URDF a model file names for its pose-dependent terms (``urdf``; docs/model_file.md).

    Plain data plus the evaluator the adapter that read the file attaches (a
    :class:`frf_ident.io.kinematics.Kinematics`): the core never reads a URDF.

    Parameters
    ----------
    file : str
        Path of the URDF (absolute once loaded).
    evaluator : object, optional
        Has ``inertial_torque(q, v, a)`` and ``gravity_torque(q)``, arrays (N, n) in axis
        order: the URDF's link-side inertia and Coriolis torque, and its gravity, on the motor
        side. None until an adapter attaches it.

    """

    file: str
    evaluator: Any = field(default=None, compare=False, repr=False)

    def _read(self) -> Any:
        if self.evaluator is None:
            raise ModelFileError(f'urdf: {self.file} has not been read: load the model file '
                                 f'with frf_ident.io.model_file.load_model (pinocchio, extra '
                                 f'[kinematics], evaluates it)')
        return self.evaluator

    def inertia(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Return the URDF's inertia and Coriolis torques, shape (N, n), on the motor side."""
        return np.asarray(self._read().inertial_torque(q, v, a), dtype=float)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """Return the URDF's gravity torques, shape (N, n), on the motor side."""
        return np.asarray(self._read().gravity_torque(q), dtype=float)


@dataclass
class RobotParams:
    """
    A multi-axis flexible-joint robot: axes plus optional link-side inertial coupling.

    ``link_coupling`` is an (n, n) symmetric matrix of off-diagonal link inertia terms [kg m^2]
    (diagonal ignored); the link inertia matrix is diag(link_inertia) + offdiag(link_coupling).

    Parameters
    ----------
    axes : list of AxisParams
        The n axes, in joint order.
    link_coupling : ndarray, shape (n, n), optional
        Symmetric off-diagonal link inertia terms [kg m^2]; None (default): no coupling.
    sample_rate : float, optional
        Sample rate of the simulation and controller [Hz].
    substeps : int, optional
        Integration substeps per sample of the simulation (>= 1).
    velocity_from_encoder : bool, optional
        Measure velocity as the difference of quantised positions over one sample (like a
        real drive) instead of the true motor velocity.
    seed : int, optional
        Seed of the simulated measurement noise.
    mjcf : MjcfSource, optional
        The MJCF these parameters were linearised from (a model file's ``mjcf``); None: a
        model of our own.

    Raises
    ------
    ModelFileError
        No axes, a non-positive ``sample_rate``, ``substeps`` < 1 or not an integer, a negative
        ``seed``, a ``link_coupling`` that is not an n x n symmetric matrix, a gravity term
        naming an unknown joint, or a link inertia matrix that is not positive definite.

    """

    axes: list[AxisParams]
    link_coupling: np.ndarray | None = None
    sample_rate: float = 1000.0
    substeps: int = 2
    velocity_from_encoder: bool = False
    seed: int = 0
    mjcf: MjcfSource | None = None
    urdf: UrdfSource | None = None

    def __post_init__(self) -> None:
        if not self.axes:
            raise ModelFileError('model has no axes')
        if not (self.sample_rate > 0):
            raise ModelFileError(f'sample_rate={self.sample_rate!r} must be positive')
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise ModelFileError(f'substeps={self.substeps!r} must be an integer >= 1')
        if int(self.seed) != self.seed or self.seed < 0:
            raise ModelFileError(f'seed={self.seed!r} must be an integer >= 0')
        n = len(self.axes)
        if self.link_coupling is not None:
            c = np.asarray(self.link_coupling, dtype=float)
            if c.shape != (n, n):
                raise ModelFileError(f'link_coupling must be a {n}x{n} matrix (one row and '
                                     f'column per axis), got shape {c.shape}')
            if not np.all(np.isfinite(c)):
                raise ModelFileError('link_coupling must be finite numbers, got '
                                     f'{c.tolist()}')
            if not np.allclose(c, c.T):
                i, j = np.unravel_index(int(np.argmax(np.abs(c - c.T))), c.shape)
                raise ModelFileError(f'link_coupling is not symmetric: [{i}][{j}]='
                                     f'{c[i, j]:g} but [{j}][{i}]={c[j, i]:g}')
            self.link_coupling = c
        for a in self.axes:
            for k in range(len(a.gravity)):
                a.gravity_joints(self.joint_names, k)
            for key in ('urdf_inertia', 'urdf_gravity'):
                if getattr(a, key) and self.urdf is None:
                    raise ModelFileError(f'axis {a.name}: {key}={getattr(a, key)!r} needs the '
                                         f"model file's urdf (the robot's URDF it is a share "
                                         f'of)')
        if np.any(np.linalg.eigvalsh(self.link_inertia_matrix()) <= 0):
            raise ModelFileError('link inertia matrix (link_inertia + link_coupling) must be '
                                 'positive definite')
        if np.any(np.linalg.eigvalsh(self.rigid_link_inertia_matrix()) <= 0):
            raise ModelFileError("link inertia matrix without the second modes' inertia must be "
                                 'positive definite (a second_mode.inertia too large for the '
                                 'link coupling)')

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    @property
    def dt(self) -> float:
        return 1.0 / self.sample_rate

    @property
    def joint_names(self) -> list[str]:
        return [a.name for a in self.axes]

    def link_inertia_matrix(self) -> np.ndarray:
        """
        Return the link inertia matrix M_o.

        Returns
        -------
        ndarray, shape (n, n)
            diag(link_inertia) plus the off-diagonal terms of ``link_coupling`` [kg m^2].

        """
        m = np.diag([a.link_inertia for a in self.axes]).astype(float)
        if self.link_coupling is not None:
            off = self.link_coupling - np.diag(np.diag(self.link_coupling))
            m = m + off
        return m

    def rigid_link_inertia_matrix(self) -> np.ndarray:
        """
        Return the link inertia matrix without the inertia the second modes carry on springs.

        Returns
        -------
        ndarray, shape (n, n)
            :meth:`link_inertia_matrix` minus diag(``second_mode.inertia``) (0 where an axis
            has none) [kg m^2]: what moves rigidly with the link positions.

        """
        return self.link_inertia_matrix() - np.diag(
            [float(a.second_mode['inertia']) if a.second_mode else 0.0 for a in self.axes])

    def gravity_load(self, q_link: np.ndarray) -> np.ndarray:
        """
        Return the link-side load torque of every axis.

        Link-side load torque of every axis [N m] at link positions ``q_link`` (..., n):
        constant ``gravity_torque`` plus the ``gravity`` terms G sin(sum q_j + phi).

        Parameters
        ----------
        q_link : array_like, shape (..., n)
            Link positions [rad], the last axis in joint order.

        Returns
        -------
        ndarray, shape (..., n)
            Link-side load torque [N m] of every axis.

        """
        q = np.asarray(q_link, dtype=float)
        out = np.zeros(q.shape) + np.array([a.gravity_torque for a in self.axes])
        names = self.joint_names
        for i, a in enumerate(self.axes):
            for k, g in enumerate(a.gravity):
                arg = sum(q[..., j] for j in a.gravity_joints(names, k))
                out[..., i] += float(g['amplitude']) * np.sin(arg + float(g.get('phase', 0.0)))
        return out

    def urdf_torque(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """
        Return each axis' share of its URDF's torques (``urdf_inertia``, ``urdf_gravity``).

        Parameters
        ----------
        q, v, a : ndarray, shape (N, n)
            Positions [rad], velocities [rad/s] and accelerations [rad/s^2] in axis order.

        Returns
        -------
        ndarray, shape (N, n)
            The motor-side torque [N m]; zeros where no axis takes a share.

        """
        inertia = np.array([ax.urdf_inertia for ax in self.axes], dtype=float)
        gravity = np.array([ax.urdf_gravity for ax in self.axes], dtype=float)
        out = np.zeros(np.shape(q))
        if inertia.any():
            out += self.urdf.inertia(q, v, a) * inertia
        if gravity.any():
            out += self.urdf.gravity(q) * gravity
        return out

    def refuse_urdf_terms(self, what: str) -> None:
        """Raise ModelFileError when an axis takes a share of its URDF: ``what`` cannot."""
        named = [ax.name for ax in self.axes if ax.urdf_inertia or ax.urdf_gravity]
        if named:
            raise ModelFileError(
                f'axes {named}: urdf_inertia / urdf_gravity (shares of '
                f'{self.urdf.file if self.urdf else "a URDF"}) are evaluated in inverse '
                f'dynamics only; {what} holds constant inertias and sinusoid gravity (a model '
                f'written by diagnose with --urdf: set them to 0, or simulate the URDF in '
                f'MuJoCo)')

    def torque_limits(self) -> np.ndarray:
        """
        Return the torque limit of every axis.

        Returns
        -------
        ndarray, shape (n,)
            ``torque_limit`` of each axis [N m].

        """
        return np.array([a.torque_limit for a in self.axes], dtype=float)

    def with_axes(self, **changes: Any) -> 'RobotParams':
        """
        Copy with the same attribute changes applied to every axis.

        Parameters
        ----------
        **changes
            :class:`AxisParams` field names and their new values.

        Returns
        -------
        RobotParams
            A copy whose axes are copies with ``changes`` applied (validated again).

        """
        return replace(self, axes=[replace(a, **changes) for a in self.axes])

    def linear(self) -> 'RobotParams':
        """
        Return the linear part: no Coulomb friction, backlash, ripple, nonlinear stiffness.

        Returns
        -------
        RobotParams
            A copy without Coulomb friction, backlash, torque ripple, stiffening spring and
            gravity terms (``gravity_torque`` and the linear terms are kept).

        """
        return self.with_axes(coulomb_friction=0.0, backlash=0.0, torque_ripple=[],
                              stiffness_k2=None, stiffness_breakpoint=None, gravity=[])
