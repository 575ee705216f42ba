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
Who asked: one log line per run request, accepted or refused, with its caller and time.

The excitation node logs every call of /frf/run_multisine, /frf/run_iteration and /frf/abort
with what the middleware tells about the caller (frf_ident/middleware/caller.py: the node,
its enclave, host and process on the DDS backend; the service's client nodes on rclpy), the
wall time the request was taken and the verdict; a refusal's reply names the caller too.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ['RunRequest']


@dataclass(frozen=True)
class RunRequest:
    """
    One request of a run service and what became of it.

    Parameters
    ----------
    service : str
        The service called.
    at : str
        Wall time the request was taken (``frf_ident.middleware.caller.wall_time_text``).
    caller : str
        What the middleware tells of the caller (``Caller.describe()``).
    accepted : bool
        Whether a run started (for /frf/abort: whether a run was stopped).
    detail : str
        The run started (``run 3 multisine``), or the reason of the refusal.

    Examples
    --------
    >>> RunRequest('/frf/run_multisine', '2026-03-01T14:03:07.412+01:00', 'node /operator',
    ...            False, 'not armed: no operator heartbeat yet').line()[:45]
    '/frf/run_multisine refused at 2026-03-01T14:0'

    """

    service: str
    at: str
    caller: str
    accepted: bool
    detail: str

    def line(self) -> str:
        """
        Return the log line: service, verdict, time, detail, caller.

        Returns
        -------
        str
            One line.

        """
        verdict = 'accepted' if self.accepted else 'refused'
        return f'{self.service} {verdict} at {self.at}: {self.detail}; caller: {self.caller}'
