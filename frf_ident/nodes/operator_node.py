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
operator: the operator's console, the enabling device of a run on a real robot.

``ros2 run frf_ident operator [--token TOKEN] [--name WHO]`` (on the robot PC): asks for the
token excitation_node printed at its start (unless ``--token``), verifies the node's
announcement on /frf/arming with it and sends the heartbeat on /frf/heartbeat while it runs.
Lines typed: ``m``, ``i``, ``a``, ``q`` (frf_ident/app/operator_console.py). Ctrl-C, ``q`` or
a killed console stop the heartbeat, and excitation_node ramps a running run to zero within
its ``heartbeat_timeout_ms``. Wiring only: frf_ident/app/heartbeat.py makes the heartbeats.
"""
from __future__ import annotations

import argparse
import getpass
import socket
import sys
import threading
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.app.heartbeat import HeartbeatSender
from frf_ident.app.operator_console import COMMANDS, HELP, progress_line, reply_line
from frf_ident.errors import FrfIdentInputError
from frf_ident.nodes import common as c

__all__ = ['main', 'OperatorNode']

#: how long a command waits for the excitation node's reply [s] (planning takes seconds)
CALL_TIMEOUT_S = 120.0


def say(text: str) -> None:
    """Print one line for the operator."""
    print(f'operator: {text}', flush=True)


class OperatorNode:
    """
    Heartbeat publisher, announcement and progress subscriptions, and the command clients.

    Parameters
    ----------
    node : Any
        The node.
    sender : HeartbeatSender
        Holds the token; makes the heartbeats.

    """

    def __init__(self, node: Any, sender: HeartbeatSender) -> None:
        self.node, self.sender = node, sender
        t = c.topics(node, ('arming_topic', 'heartbeat_topic', 'progress_topic'))
        self.String = mw.msg('std_msgs/msg/String')
        self.pub = node.create_publisher(self.String, t['heartbeat_topic'], mw.qos_default(1))
        node.create_subscription(self.String, t['arming_topic'], self._on_announcement,
                                 mw.qos_transient_local(1))
        node.create_subscription(self.String, t['progress_topic'], self._on_progress,
                                 mw.qos_transient_local(10))
        self.Trigger = mw.srv('std_srvs/srv/Trigger')
        #: created at a command's first use: until then this console is no client of the run
        #: services, so rclpy can name another caller (middleware/caller.py)
        self.clients: dict[str, Any] = {}
        self.stop = threading.Event()
        say('waiting for excitation_node on /frf/arming; ' + HELP)

    def _on_announcement(self, msg: Any) -> None:
        say(self.sender.on_announcement(msg.data))

    def _on_progress(self, msg: Any) -> None:
        line = progress_line(msg.data)
        if line is not None:
            say(line)

    def _beat(self) -> None:
        """Send the heartbeats, in a thread of their own (no executor between them)."""
        while not self.stop.wait(self.sender.period_s):
            text = self.sender.next_heartbeat()
            if text is not None:
                self.pub.publish(self.String(data=text))

    def _commands(self) -> None:
        for line in sys.stdin:
            key = line.strip().lower()[:1]
            if key == 'q':
                break
            if key not in COMMANDS:
                if key:
                    say(HELP)
                continue
            if key not in self.clients:
                self.clients[key] = self.node.create_client(self.Trigger, COMMANDS[key])
            try:
                reply = self.clients[key].call(self.Trigger.Request(), CALL_TIMEOUT_S)
                say(reply_line(COMMANDS[key], reply.message))
            except TimeoutError as exc:
                say(f'{COMMANDS[key]}: no answer ({exc})')
        else:
            return                  # end of input (no terminal): run until Ctrl-C
        say('quit: heartbeat stopped')
        self.stop.set()
        wake = getattr(self.node, 'wake', None)
        if wake is not None:
            wake()

    def spin(self, stop: threading.Event) -> None:
        """Spin until Ctrl-C or ``q``; commands are read in a thread of their own."""
        self.stop = stop
        threading.Thread(target=self._commands, daemon=True).start()
        threading.Thread(target=self._beat, daemon=True).start()
        mw.spin(self.node, stop)


def _token(given: Optional[str]) -> str:
    if given:
        return given
    if sys.stdin.isatty():
        return getpass.getpass('operator: token printed by excitation_node: ')
    return sys.stdin.readline()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """
    ``ros2 run frf_ident operator``.

    Parameters
    ----------
    argv : sequence of str, optional
        Command line (``--token``, ``--name``, then ``--ros-args`` ...); default sys.argv.

    Returns
    -------
    int
        0, or 2 for a malformed token.

    """
    args = list(sys.argv if argv is None else argv)
    own = args[1:args.index('--ros-args')] if '--ros-args' in args else args[1:]
    p = argparse.ArgumentParser(prog='operator', description=__doc__.split('\n\n')[0])
    p.add_argument('--token', help='the token excitation_node printed (asked if not given)')
    p.add_argument('--name', default=f'{getpass.getuser()}@{socket.gethostname()}',
                   help='who runs this console (in every heartbeat and the node log)')
    opts = p.parse_args(own)
    try:
        sender = HeartbeatSender(_token(opts.token), opts.name)
    except FrfIdentInputError as exc:
        print(f'operator: {exc}', file=sys.stderr, flush=True)
        return 2
    rest = [args[0]] + args[len(own) + 1:]
    return c.run_node('operator', lambda node: OperatorNode(node, sender), rest,
                      use_sim_time=False)


if __name__ == '__main__':
    raise SystemExit(main())
