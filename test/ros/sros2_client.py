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
One participant's attempt to call /frf/run_multisine, for test/ros/test_ros_sros2.py.

``python sros2_client.py NODE WAIT_S [--ros-args --enclave ENCLAVE]`` (security from the
environment: ROS_SECURITY_*). It subscribes /frf/arming (the excitation node's latched
announcement: does this participant see the node at all?), creates a client of
/frf/run_multisine, waits up to WAIT_S for the service, calls it whether it was discovered or
not, waits up to WAIT_S for the answer (and for the announcement up to 2 WAIT_S in all), and
prints one line ``SROS2_CLIENT {json}``:
``created`` (the client; ``error`` if not), ``discovered`` (and ``discover_s``), ``answered``
(and ``answer``, the reply's message, ``answer_s``), ``arming_seen``.
"""
import json
import sys
import time


def main(argv):
    """Attempt the call and print what was observed; exit 0 unless rclpy itself failed."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String
    from std_srvs.srv import Trigger

    name, wait_s = argv[1], float(argv[2])
    out = {'node': name, 'created': False, 'error': '', 'discovered': False,
           'answered': False, 'arming_seen': False}
    rclpy.init(args=argv)
    try:
        node = rclpy.create_node(name)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(String, '/frf/arming',
                                 lambda m: out.update(arming_seen=True), latched)
        try:
            client = node.create_client(Trigger, '/frf/run_multisine')
            out['created'] = True
        except Exception as e:              # the participant's own access control refused
            out['error'] = f'{type(e).__name__}: {e}'
            client = None
        t0 = time.monotonic()
        while client is not None and time.monotonic() - t0 < wait_s:
            rclpy.spin_once(node, timeout_sec=0.1)
            if client.service_is_ready():
                out.update(discovered=True, discover_s=round(time.monotonic() - t0, 2))
                break
        if client is not None:
            t1 = time.monotonic()
            future = client.call_async(Trigger.Request())
            rclpy.spin_until_future_complete(node, future, timeout_sec=wait_s)
            if future.done() and future.result() is not None:
                out.update(answered=True, answer=future.result().message,
                           answer_s=round(time.monotonic() - t1, 2))
        while not out['arming_seen'] and time.monotonic() - t0 < 2 * wait_s:
            rclpy.spin_once(node, timeout_sec=0.1)
        node.destroy_node()
    except Exception as e:                  # the node itself could not be made
        out['error'] = out['error'] or f'{type(e).__name__}: {e}'
    finally:
        rclpy.try_shutdown()
    print('SROS2_CLIENT ' + json.dumps(out), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
