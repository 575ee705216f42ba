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
The shipped SROS2 policy (config/sros2/frf_ident_policy.xml) against the code and its purpose.

Without ROS 2: this machine has no sros2 and no copy of its policy schema; secure mode runs
in test/ros/test_ros_sros2.py (a keystore made by frf_ident/io/sros2_keystore.py, Cyclone
DDS's security plugins, Enforce). What is checked here: the policy's structure as the ROS 2
access-control design defines it (policy version 0.2.0, enclaves > enclave[path] > profiles >
profile[ns, node] > topics|services with publish/subscribe or request/reply = ALLOW|DENY),
that its names are the ones the nodes use, and the property issue 56 asks for: only the
operator's enclave may call the run services.
"""
from pathlib import Path
import xml.etree.ElementTree as ET

from frf_ident.app.operator_console import COMMANDS
from frf_ident.nodes.common import LIVE_FRAMES, TOPICS

POLICY = Path(__file__).resolve().parents[1] / 'config' / 'sros2' / 'frf_ident_policy.xml'
RULES = {'topics': ({'publish', 'subscribe'}, 'topic'),
         'services': ({'request', 'reply'}, 'service')}
RUN_SERVICES = {'frf/run_multisine', 'frf/run_iteration'}
#: the node ``ros2 service call SERVICE std_srvs/srv/Trigger`` creates (ros2cli)
ROS2CLI_TRIGGER = '_ros2cli_requester_std_srvs_Trigger'
#: the live estimate's topics (frf_ident/nodes/common.py: live_topic + LIVE_FRAMES)
LIVE = {f"{TOPICS['live_topic'].lstrip('/')}/{k}" for k in LIVE_FRAMES}


def _grants():
    """(enclave, node, kind, permission, name) for every ALLOW in the policy."""
    root = ET.parse(POLICY).getroot()
    assert root.tag == 'policy' and root.get('version') == '0.2.0'
    assert [c.tag for c in root] == ['enclaves']
    out = []
    for enclave in root.find('enclaves'):
        assert enclave.tag == 'enclave' and enclave.get('path', '').startswith('/')
        assert [c.tag for c in enclave] == ['profiles']
        for profile in enclave.find('profiles'):
            assert profile.tag == 'profile' and profile.get('ns') == '/'
            for rule in profile:
                allowed, child = RULES[rule.tag]
                assert set(rule.attrib) <= allowed and rule.attrib, rule.attrib
                assert set(rule.attrib.values()) <= {'ALLOW', 'DENY'}
                for obj in rule:
                    assert obj.tag == child and obj.text and not obj.text.startswith('/')
                    for perm, value in rule.attrib.items():
                        if value == 'ALLOW':
                            out.append((enclave.get('path'), profile.get('node'), rule.tag,
                                        perm, obj.text))
    return out


def _who(grants, kind, perm, name):
    return {e for e, _n, k, p, o in grants if (k, p, o) == (kind, perm, name)}


def test_only_the_operator_enclave_calls_the_run_services():
    g = _grants()
    for service in RUN_SERVICES:
        assert _who(g, 'services', 'request', service) == {'/frf_ident/operator'}, service
        assert _who(g, 'services', 'reply', service) == {'/frf_ident/excitation'}, service


def test_only_the_excitation_node_moves_the_robot_and_only_the_operator_enables_it():
    g = _grants()
    assert _who(g, 'topics', 'publish', 'velocity_controller/commands') == {
        '/frf_ident/excitation'}
    assert _who(g, 'topics', 'publish', 'frf/heartbeat') == {'/frf_ident/operator'}


def test_policy_names_are_the_nodes_names():
    g = _grants()
    topics = {v.lstrip('/') for v in TOPICS.values()} | LIVE
    services = {s.lstrip('/') for s in COMMANDS.values()}
    node_common = {'rosout', 'parameter_events'}     # and '~/...' parameter services
    for _e, node, kind, _p, name in g:
        if name in node_common or name.startswith('~/'):
            continue
        assert name in (topics if kind == 'topics' else services), name
        assert node in {'excitation_node', 'excitation_node_arming', 'operator',
                        'estimator_node', ROS2CLI_TRIGGER}, node


def test_ros2_service_call_has_a_profile_in_the_operator_enclave_only():
    """
    The documented ``ros2 service call`` under the operator enclave needs its node's profile.

    Under Enforce every entity a node creates needs a grant: without a profile for the node
    ros2cli makes (its parameter services) the call fails before sending anything ("failed
    to create topic [rr/_ros2cli_requester_std_srvs_Trigger/describe_parametersReply]",
    seen live, test/ros/test_ros_sros2.py).
    """
    g = _grants()
    assert {e for e, n, *_ in g if n == ROS2CLI_TRIGGER} == {'/frf_ident/operator'}
    own = {o for e, n, k, p, o in g if n == ROS2CLI_TRIGGER and (k, p) == ('services', 'reply')}
    assert '~/describe_parameters' in own and '~/get_type_description' in own


def test_every_topic_the_nodes_create_is_granted():
    """
    The excitation node publishes, and the estimator records, the live estimate and warnings.

    Under Enforce a publisher without a grant is not created at all: the excitation node
    died at start-up with "failed to create topic [rt/frf/live/frf]" once the live estimate
    came (issue 52) and the policy did not list it.
    """
    g = _grants()
    published = {o for e, _n, k, p, o in g
                 if (e, k, p) == ('/frf_ident/excitation', 'topics', 'publish')}
    recorded = {o for e, _n, k, p, o in g
                if (e, k, p) == ('/frf_ident/estimator', 'topics', 'subscribe')}
    kinds = ('progress_topic', 'warnings_topic', 'experiment_topic', 'excitation_topic')
    own = {TOPICS[k].lstrip('/') for k in kinds}
    assert LIVE | own <= published
    assert LIVE | own <= recorded
