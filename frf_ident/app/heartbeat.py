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
The operator heartbeat's wire format: the one-time token, the MACs, the console's sender.

/frf/heartbeat carries ``{"session", "console", "seq", "operator", "mac"}`` (std_msgs/String
JSON); ``mac`` is HMAC-SHA256, keyed with the session's token, of the other fields; the
announcement on /frf/arming carries a MAC of its session and node the same way. Why this
keeps a replayed bag from arming a node: frf_ident/app/arming.py. No I/O here.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import secrets
from typing import Any, Optional

from frf_ident.errors import FrfIdentInputError

__all__ = ['announcement_mac', 'heartbeat_mac', 'HeartbeatSender', 'make_token',
           'normalise_token']

#: the console's heartbeat period before it took an announcement [s] (the node announces
#: its own: heartbeat_timeout_ms / HEARTBEATS_PER_TIMEOUT of frf_ident/app/arming.py)
DEFAULT_PERIOD_S = 0.05

#: the token: 12 symbols of Crockford's base32 (60 bits, new at every node start)
ALPHABET = '0123456789ABCDEFGHJKMNPQRSTVWXYZ'
TOKEN_LENGTH = 12
#: what the MACs sign, before the fields (a version, so a changed format never verifies)
HEARTBEAT_DOMAIN = 'frf_ident heartbeat v1'
ANNOUNCE_DOMAIN = 'frf_ident arming v1'


def make_token() -> str:
    """
    Return a new one-time token, ``XXXX-XXXX-XXXX`` (60 random bits).

    Returns
    -------
    str
        Twelve symbols of Crockford's base32 in three groups.

    """
    s = ''.join(secrets.choice(ALPHABET) for _ in range(TOKEN_LENGTH))
    return '-'.join(s[i:i + 4] for i in range(0, TOKEN_LENGTH, 4))


def normalise_token(text: str) -> str:
    """
    Return the token as typed, without separators and with look-alikes mapped.

    Parameters
    ----------
    text : str
        The token as the operator typed it (case, '-' and spaces do not matter; O is 0,
        I and L are 1).

    Returns
    -------
    str
        Twelve upper-case symbols.

    Raises
    ------
    FrfIdentInputError
        Not twelve symbols of the alphabet.

    Examples
    --------
    >>> normalise_token('7k3p-9qxd-m2tf')
    '7K3P9QXDM2TF'

    """
    s = text.strip().upper().replace('-', '').replace(' ', '')
    s = s.translate(str.maketrans('OIL', '011'))
    if len(s) != TOKEN_LENGTH or any(ch not in ALPHABET for ch in s):
        raise FrfIdentInputError(f'token {text.strip()!r}: expected the {TOKEN_LENGTH} symbols '
                                 'excitation_node printed at start (XXXX-XXXX-XXXX)')
    return s


def _mac(token: str, *fields: Any) -> str:
    msg = '|'.join(str(f) for f in fields).encode()
    return hmac.new(normalise_token(token).encode(), msg, hashlib.sha256).hexdigest()


def heartbeat_mac(token: str, session: str, console: str, seq: int, operator: str) -> str:
    """
    Return the MAC of one heartbeat (hex HMAC-SHA256 keyed with the token).

    Parameters
    ----------
    token : str
        The session's token.
    session : str
        The session nonce of /frf/arming.
    console : str
        The console's random id.
    seq : int
        The heartbeat's sequence number (increasing per console).
    operator : str
        Who the console says runs it (``user@host``).

    Returns
    -------
    str
        64 hex digits.

    """
    return _mac(token, HEARTBEAT_DOMAIN, session, console, int(seq), operator)


def announcement_mac(token: str, session: str, node: str) -> str:
    """
    Return the MAC of a node's announcement: a console with the token knows it is its node's.

    Parameters
    ----------
    token : str
        The session's token.
    session : str
        The session nonce.
    node : str
        The announcing node's name.

    Returns
    -------
    str
        64 hex digits.

    """
    return _mac(token, ANNOUNCE_DOMAIN, session, node)


class HeartbeatSender:
    """
    The operator console's side: verify the node's announcement, make the heartbeats.

    Parameters
    ----------
    token : str
        The token the node printed (as typed).
    operator : str
        Who runs the console (``user@host``), signed into every heartbeat.

    Raises
    ------
    FrfIdentInputError
        The token is malformed.

    """

    def __init__(self, token: str, operator: str) -> None:
        self.token = normalise_token(token)
        self.operator = operator
        self.console = secrets.token_hex(8)
        self.seq = 0
        #: the announcement taken (its session is what the heartbeats carry)
        self.session: Optional[str] = None
        self.node = ''
        self.period_s = DEFAULT_PERIOD_S
        self.armed = False

    def on_announcement(self, text: str) -> str:
        """
        Take an announcement of /frf/arming; return one line for the operator.

        Parameters
        ----------
        text : str
            Its JSON.

        Returns
        -------
        str
            What changed: armed, unarmed with the node's reason, or why it was ignored.

        """
        try:
            a = json.loads(text)
            session, node, mode = str(a['session']), str(a['node']), str(a['arming'])
        except (ValueError, KeyError, TypeError) as exc:
            return f'ignored an announcement on /frf/arming that is no JSON object: {exc}'
        if mode == 'off':
            return f'{node} needs no arming (arming: off, a simulation)'
        if not hmac.compare_digest(str(a.get('mac', '')),
                                   announcement_mac(self.token, session, node)):
            return (f'ignored the announcement of {node} session {session[:8]}: not made with '
                    'this token (another start of the node, a replayed bag, or a mistyped '
                    'token)')
        new = session != self.session
        self.session, self.node = session, node
        self.period_s = float(a['heartbeat_period_ms']) * 1e-3
        self.armed = bool(a['armed'])
        state = 'ARMED: runs may start' if self.armed else str(a.get('reason'))
        head = f'{node} session {session[:8]}: ' if new else f'{node}: '
        return head + state

    def next_heartbeat(self) -> Optional[str]:
        """
        Return the next heartbeat's JSON, or None before a verified announcement.

        Returns
        -------
        str or None
            ``{"session", "console", "seq", "operator", "mac"}``.

        """
        if self.session is None:
            return None
        self.seq += 1
        return json.dumps({'session': self.session, 'console': self.console, 'seq': self.seq,
                           'operator': self.operator,
                           'mac': heartbeat_mac(self.token, self.session, self.console,
                                                self.seq, self.operator)})
