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
The diagnosis against an MJCF: every candidate model simulated as the MJCF it would write.

``frf-ident diagnose`` with a model file naming an MJCF injects a :class:`MjcfModels` into the
diagnosis as its simulator (:class:`frf_ident.core.diagnosis.common.Simulator`): a candidate
model (the nominal MJCF read in our parameters, with diagnosed changes) is turned into the
MJCF's drive terms (:func:`~frf_ident.io.mjcf.held.held_drives`), written into the nominal
MJCF (:func:`~frf_ident.io.mjcf.export.drive_spec`) and simulated by MuJoCo in the closed loop
of the record (:class:`~frf_ident.io.mjcf.plant.MujocoPlant`). So the rigid body is MuJoCo's
own (M(q), Coriolis, gravity along the motion, not our linearisation at the pose), and what
the diagnosis judges is exactly what ``extended_model.xml`` holds (:meth:`MjcfModels.write`).
What the MJCF cannot hold is simulated as written instead (the closest MJCF) and reported.

Our plant cannot stand in: our view of a rigid MJCF joint (a spring 20 Nyquist frequencies up
behind 1 % of its inertia) makes the sampled velocity PI of a real arm unstable.
"""
from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

from frf_ident.core.diagnosis.common import as_simulation, drive_reference
from frf_ident.core.model.params import MjcfSource, RobotParams
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.drive_map import JointDrive, MODE_SUFFIX
from frf_ident.io.mjcf.export import drive_spec, MjcfExport, write_drives
from frf_ident.io.mjcf.held import Held, held_drives
from frf_ident.io.mjcf.link_mode import read_mode
from frf_ident.io.mjcf.plant import MujocoPlant
from frf_ident.io.mjcf.robot import load_robot, load_spec, MjcfRobot
import mujoco
import numpy as np

__all__ = ['MjcfModels', 'read_drives', 'simulate_robot']

#: prepared MJCF models kept by their drive terms (a candidate simulated again compiles nothing)
KEEP = 8


def read_drives(robot: MjcfRobot) -> list[JointDrive]:
    """Return the drive terms the MJCF has on each axis (MJCF -> JointDrive)."""
    m = robot.model
    out = []
    for i, name in enumerate(robot.axes):
        v, lv = robot.vadr[i], robot.link_vadr[i]
        mj = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name + MODE_SUFFIX)
        mode = {} if mj < 0 else dict(zip(('mode_inertia', 'mode_stiffness', 'mode_damping'),
                                          read_mode(m, mj)))
        out.append(JointDrive(
            name, armature=float(m.dof_armature[v]), damping=float(m.dof_damping[v]),
            frictionloss=float(m.dof_frictionloss[v]),
            stiffness=float(m.jnt_stiffness[m.dof_jntid[lv]]) if lv >= 0 else None,
            link_damping=float(m.dof_damping[lv]) if lv >= 0 else 0.0,
            torque_limit=float(robot.torque_limit[i]),
            delay=float(m.actuator_delay[robot.actuator[i]]), **mode))
    return out


def simulate_robot(robot: MjcfRobot, rec: Recording, ctrl: PIVelocity, *,
                   reference: np.ndarray | None = None) -> Recording:
    """
    Simulate a prepared MJCF in closed loop on ``rec``'s reference, like the record.

    As :func:`frf_ident.core.diagnosis.common.simulate_like` does for our plant: at rest at
    the pose, the PI (``ctrl`` at the record's rate) starting with the holding torque, no
    measurement noise; the result carries ``rec``'s segments. ``reference`` defaults to
    :func:`~frf_ident.core.diagnosis.common.drive_reference` of ``rec``.
    """
    r = drive_reference(rec) if reference is None else reference
    axes = [{'name': a} for a in robot.axes]
    plant = MujocoPlant({'axes': axes, 'sample_rate': rec.fs}, robot=robot)
    c = ctrl.copy()
    c.dt = rec.dt
    c.reset(plant.hold)
    res = plant.simulate(reference=r, controller=c)
    return as_simulation(rec, res.position, res.velocity, res.effort)


class MjcfModels:
    """
    The nominal MJCF and every model of the diagnosis as that MJCF with drive terms.

    Parameters
    ----------
    nominal : RobotParams
        The model file naming the MJCF, read in our parameters (``nominal.mjcf`` set).

    Raises
    ------
    MjcfError
        The model names no MJCF.

    """

    #: the effects of the diagnosis' vocabulary an MJCF cannot hold (docs/mujoco.md): the
    #: diagnosis does not offer them (it could not judge them) and names them in ``rejected``
    unheld = {
        'stiffness_nonlinearity': 'MuJoCo holds no breakpoint spring (MuJoCo 4: a polynomial '
                                  'stiffness k1 c2 c3; not fitted here)',
        'backlash': 'MuJoCo has no dead zone on a joint spring',
        'torque_ripple': 'MuJoCo has no position-periodic joint torque',
        'gravity': "the MJCF's bodies hold gravity: a different one means wrong masses or "
                   'centres of mass, which the diagnosis does not fit'}

    def __init__(self, nominal: RobotParams) -> None:
        if nominal.mjcf is None:
            raise MjcfError('the diagnosis against an MJCF needs a model file naming one')
        self.nominal = nominal
        self.source: MjcfSource = nominal.mjcf
        self.text = load_spec(self.source.file).to_xml()
        robot = load_robot(self.source, nominal.joint_names)
        self.base = read_drives(robot)
        self.timestep = float(robot.model.opt.timestep)
        self._kept: OrderedDict[str, MjcfRobot] = OrderedDict()

    def step(self, robot: RobotParams) -> float:
        """
        Return MuJoCo's time step for ``robot`` [s].

        The MJCF's, divided as ``robot.substeps`` exceeds the nominal's (the diagnosis'
        integrator check simulates at twice the substeps: MuJoCo at half the step).
        """
        return self.timestep * self.nominal.substeps / robot.substeps

    def held(self, robot: RobotParams) -> Held:
        """Return ``robot`` as the MJCF's drive terms and what the MJCF cannot hold."""
        return held_drives(robot, self.nominal, self.base, self.step(robot))

    def spec(self, robot: RobotParams) -> mujoco.MjSpec:
        """Return the nominal MJCF with ``robot``'s drive terms (not compiled)."""
        return drive_spec(mujoco.MjSpec.from_string(self.text), self.held(robot).drives,
                          timestep=self.step(robot))

    def prepared(self, robot: RobotParams) -> MjcfRobot:
        """Return ``robot`` as an MJCF prepared for simulation (the other joints locked)."""
        held = self.held(robot)
        key = repr((held.drives, self.step(robot)))
        if key not in self._kept:
            spec = drive_spec(mujoco.MjSpec.from_string(self.text), held.drives,
                              timestep=self.step(robot))
            self._kept[key] = load_robot(self.source, robot.joint_names, spec=spec)
            while len(self._kept) > KEEP:
                self._kept.popitem(last=False)
        return self._kept[key]

    def __call__(self, rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
                 reference: np.ndarray | None = None) -> Recording:
        """
        Simulate ``robot`` as MJCF in MuJoCo on the record's reference (a diagnosis Simulator).

        As :func:`frf_ident.core.diagnosis.common.simulate_like`: at rest at the pose, the PI
        starting with the holding torque, no measurement noise; ``rec``'s segments.
        """
        return simulate_robot(self.prepared(robot), rec, ctrl, reference=reference)

    def write(self, robot: RobotParams, path: str | Path) -> MjcfExport:
        """
        Write ``robot`` as the nominal MJCF with its drive terms; say what it cannot hold.

        ``mujoco.MjModel.from_xml_path`` loads the file; it is the model :meth:`__call__`
        simulates (the same drive terms and time step).
        """
        path = Path(path)
        spec, modes = write_drives(mujoco.MjSpec.from_string(self.text),
                                   self.held(robot).drives, timestep=self.step(robot),
                                   link_inertia={a.name: a.link_inertia for a in robot.axes})
        spec.compile()
        path.write_text(spec.to_xml())
        step = self.step(robot)
        notes = [] if step == self.timestep else [
            f'option timestep {step:g} s (the MJCF has {self.timestep:g} s): the integrator '
            f'check found the coarser step moves the simulation']
        return MjcfExport(path, self.held(robot).limitations + modes, notes)
