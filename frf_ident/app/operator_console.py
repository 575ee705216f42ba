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
What the operator console (``ros2 run frf_ident operator``) shows and understands.

Commands, one per line on its terminal: ``m`` runs the multisine, ``i`` one chirp iteration,
``a`` aborts, ``q`` (or Ctrl-C) quits, which stops the heartbeat: a running excitation ramps
to zero. Each progress event of /frf/progress and each reply becomes one short line.
"""
from __future__ import annotations

import json
from typing import Optional

__all__ = ['COMMANDS', 'progress_line', 'reply_line']

#: command letter -> service the console calls
COMMANDS = {'m': '/frf/run_multisine', 'i': '/frf/run_iteration', 'a': '/frf/abort'}
HELP = ('commands: m = run the multisine, i = one chirp iteration, a = abort, q = quit '
        '(stops the heartbeat: a running excitation ramps to zero)')


def progress_line(text: str) -> Optional[str]:
    """
    Return one line for a /frf/progress event, None for the periodic ones.

    Parameters
    ----------
    text : str
        The event's JSON.

    Returns
    -------
    str or None
        ``run 3 multisine started`` / ``finished`` / ``ABORTED: <reason>``.

    Examples
    --------
    >>> progress_line('{"event": "finished", "run": 2, "procedure": "multisine", '
    ...               '"success": false, "aborted": true, "error": "operator heartbeat lost"}')
    'run 2 multisine ABORTED: operator heartbeat lost'

    """
    try:
        e = json.loads(text)
        event, head = e['event'], f"run {e['run']} {e['procedure']}"
    except (ValueError, KeyError, TypeError):
        return None
    if event == 'started':
        return f'{head} started ({e.get("of", "?")} samples)'
    if event != 'finished':
        return None
    if e.get('aborted'):
        return f'{head} ABORTED: {e.get("error")}'
    if not e.get('success'):
        return f'{head} failed: {e.get("error")}'
    return f'{head} finished'


def reply_line(service: str, text: str) -> str:
    """
    Return one line for a service reply.

    Parameters
    ----------
    service : str
        The service called.
    text : str
        The reply's message (JSON from the excitation node).

    Returns
    -------
    str
        ``accepted: run 3 multisine`` or ``refused: <reason>``.

    """
    try:
        r = json.loads(text)
    except ValueError:
        return f'{service}: {text}'
    if r.get('accepted') or r.get('aborted'):
        return f"{service}: {'accepted' if 'accepted' in r else 'aborted'} run {r.get('run')}"
    return f"{service}: refused: {r.get('error')}"
