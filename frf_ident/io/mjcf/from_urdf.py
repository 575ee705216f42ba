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
An MJCF built from a URDF: MuJoCo reads the URDF's bodies and joints, we add torque motors.

MuJoCo's URDF import keeps the links' inertials and the joints' axes and limits (and
``actuatorfrcrange`` from ``<limit effort>``) but has no actuators; :func:`mjcf_from_urdf` adds a
``motor`` on every hinge with ``ctrlrange`` from the given torque limits (else the URDF's
effort), sets the time step and MuJoCo's ``implicitfast`` integrator, balances inertias that
violate the triangle inequality (``compiler balanceinertia``, which URDFs written by hand often
need) and writes the MJCF. The result is a nominal model or a plant like the shared iiwa 14
(e.g. the repository's urdf/kuka_kr300_axes123.urdf, a robot that is not the iiwa).
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

from frf_ident.errors import MjcfError
import mujoco

__all__ = ['mjcf_from_urdf']


def mjcf_from_urdf(urdf: str | Path, out: str | Path, *, timestep: float = 1e-3,
                   torque_limits: Sequence[float] | None = None) -> Path:
    """
    Write an MJCF of a URDF with a torque motor on each hinge joint.

    Parameters
    ----------
    urdf : str or Path
        The URDF.
    out : str or Path
        The MJCF to write.
    timestep : float, optional
        MuJoCo's time step [s] (the sample period or a divisor of it).
    torque_limits : sequence of float, optional
        Per hinge joint, in the URDF's order [N m]; default the URDF's ``effort``.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    MjcfError
        MuJoCo cannot read the URDF, or the limits do not match its hinge joints.

    """
    p = Path(urdf)
    try:
        spec = mujoco.MjSpec.from_file(str(p))
    except (ValueError, RuntimeError) as err:
        raise MjcfError(f'{p}: MuJoCo cannot read it ({str(err).strip().splitlines()[0]})') \
            from err
    spec.compiler.balanceinertia = True
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    hinges = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    if torque_limits is not None and len(torque_limits) != len(hinges):
        raise MjcfError(f'{p}: {len(torque_limits)} torque limits for the '
                        f'{len(hinges)} hinge joints {[j.name for j in hinges]}')
    for k, j in enumerate(hinges):
        lim = float(torque_limits[k]) if torque_limits is not None \
            else float(abs(j.actfrcrange[1]))
        if not lim > 0:
            raise MjcfError(f'{p}: joint {j.name!r} has no effort limit; give torque_limits')
        act = spec.add_actuator(name=f'{j.name}_motor', target=j.name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_motor()
        act.ctrllimited = True
        act.ctrlrange = [-lim, lim]
        j.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
    spec.compile()
    out = Path(out)
    out.write_text(spec.to_xml())
    return out
