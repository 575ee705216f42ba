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
ArmingGate and the heartbeat format (frf_ident/app/arming.py, heartbeat.py), on a fake clock.

The truth here is the protocol's definition: a heartbeat verifies only with this session's
token, each console's numbers only once and rising; the gate refuses or aborts exactly at the
timeout. The graph-level behaviour (real processes, ros2 bag play) is test/ros/test_ros_arming.py.
"""
import json

from frf_ident.app.arming import ArmingGate, ArmingSettings, TIMEOUT_RANGE_MS
from frf_ident.app.heartbeat import HeartbeatSender, make_token, normalise_token
from frf_ident.errors import DesignError, FrfIdentInputError, NotArmed
from hypothesis import given, settings, strategies as st
import pytest


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def _armed_pair(timeout_ms=250.0):
    clock = Clock()
    gate = ArmingGate(ArmingSettings('token', timeout_ms), clock=clock)
    console = HeartbeatSender(gate.token, 'alice@robot-pc')
    assert 'ARMED' not in console.on_announcement(gate.announcement())
    return clock, gate, console


def test_unarmed_until_a_valid_heartbeat_and_again_after_the_timeout():
    clock, gate, console = _armed_pair()
    with pytest.raises(NotArmed, match='no operator heartbeat yet'):
        gate.check()
    assert gate.on_heartbeat(console.next_heartbeat()) is None
    gate.check()                                           # armed
    clock.t += 0.25
    gate.check()                                           # at the limit: still armed
    clock.t += 0.002
    with pytest.raises(NotArmed, match=r'stopped 252 ms ago \(limit heartbeat_timeout_ms=250\)'):
        gate.check()


def test_running_run_aborts_exactly_after_the_timeout_and_logs_its_gaps():
    clock, gate, console = _armed_pair()
    gate.on_heartbeat(console.next_heartbeat())
    clock.t += 3.0                   # planning: no heartbeat taken for seconds
    gate.run_started(7)
    assert gate.watch(7, True) == (None, None)       # the run's clock starts at its start
    for _ in range(10):
        clock.t += 0.05
        gate.on_heartbeat(console.next_heartbeat())
        assert gate.watch(7, True) == (None, None)
    clock.t += 0.25
    assert gate.watch(7, True) == (None, None)
    clock.t += 0.001
    abort, _ = gate.watch(7, True)
    assert abort.startswith('operator heartbeat lost: none for 251 ms')
    assert 'alice@robot-pc' in abort
    assert gate.watch(8, True) == (None, None)       # only the run it was told about
    _, summary = gate.watch(7, False)
    assert summary == ('operator heartbeat of run 7: longest gap 50 ms (limit '
                       'heartbeat_timeout_ms=250)')


def test_replayed_heartbeats_of_the_same_session_are_refused():
    clock, gate, console = _armed_pair()
    recorded = [console.next_heartbeat() for _ in range(5)]
    for hb in recorded:
        assert gate.on_heartbeat(hb) is None
    clock.t += 1.0                               # the operator left
    reason = gate.on_heartbeat(recorded[2])      # a bag played back
    assert 'replayed or duplicated' in reason and '#3' in reason and '#5' in reason
    assert gate.on_heartbeat(recorded[3]) is None          # logged once per reason
    with pytest.raises(NotArmed, match='replayed or duplicated'):
        gate.check()


def test_heartbeats_of_another_session_or_token_never_arm():
    _, old_gate, old_console = _armed_pair()
    recorded = [old_console.next_heartbeat() for _ in range(3)]
    _, gate, _ = _armed_pair()                   # a new start of the node
    assert 'another session' in gate.on_heartbeat(recorded[0])
    # the old session's announcement is recognised as foreign by a console of the new token
    fresh = HeartbeatSender(gate.token, 'bob@pc')
    assert 'ignored the announcement' in fresh.on_announcement(old_gate.announcement())
    assert fresh.next_heartbeat() is None        # it sends nothing for a foreign session
    # a console with a wrong token: its MAC does not verify
    wrong = HeartbeatSender(make_token(), 'eve@laptop')
    a = json.loads(gate.announcement())
    wrong.session, wrong.node = a['session'], a['node']       # forged from the wire
    assert 'MAC does not verify' in gate.on_heartbeat(wrong.next_heartbeat())
    with pytest.raises(NotArmed):
        gate.check()


@settings(max_examples=200, deadline=None)
@given(field=st.sampled_from(['session', 'console', 'seq', 'operator']),
       junk=st.text(min_size=1, max_size=20))
def test_any_changed_field_breaks_the_mac(field, junk):
    """A heartbeat with any field changed is refused (the MAC covers every field)."""
    _, gate, console = _armed_pair()
    hb = json.loads(console.next_heartbeat())
    hb[field] = (hb[field] + 1000) if field == 'seq' else hb[field] + junk
    assert gate.on_heartbeat(json.dumps(hb)) is not None
    with pytest.raises(NotArmed):
        gate.check()


def test_malformed_heartbeat_is_refused_with_its_reason():
    _, gate, _ = _armed_pair()
    assert 'not a heartbeat' in gate.on_heartbeat('{"session": 1}')
    assert gate.on_heartbeat('no json') is None         # the same kind: logged once
    with pytest.raises(NotArmed, match='last heartbeat refused: not a heartbeat'):
        gate.check()


def test_mode_off_is_always_armed_and_announces_it():
    gate = ArmingGate(ArmingSettings('off'))
    gate.check()
    assert gate.token is None and gate.watch(1, True) == (None, None)
    console = HeartbeatSender(make_token(), 'x')
    assert 'needs no arming' in console.on_announcement(gate.announcement())


def test_settings_refuse_unknown_mode_and_timeouts_outside_the_range():
    lo, hi = TIMEOUT_RANGE_MS
    with pytest.raises(DesignError, match="arming='on'"):
        ArmingSettings('on')
    for bad in (lo - 1, hi + 1, float('nan')):
        with pytest.raises(DesignError, match='heartbeat_timeout_ms'):
            ArmingSettings('token', bad)
    assert ArmingSettings('token', 250.0).period_ms == 50.0


def test_token_format_and_typing_tolerance():
    tok = make_token()
    assert len(tok) == 14 and tok.count('-') == 2
    assert normalise_token(tok.lower().replace('-', ' ')) == tok.replace('-', '')
    assert normalise_token('o1il-0000-0000') == '011100000000'
    with pytest.raises(FrfIdentInputError, match='expected the 12 symbols'):
        normalise_token('abc')
    assert len({make_token() for _ in range(200)}) == 200
