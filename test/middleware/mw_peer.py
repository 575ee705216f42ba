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
Peer process for the two-process DDS tests: ``python mw_peer.py MODE``.

Prints ``ready`` once its endpoints exist, then serves until stdin closes.
Modes: ``publish`` (JointState + Float64MultiArray at 100 Hz), ``service`` (Trigger server on
/frf/run_iteration), ``latched`` (one transient-local /frf/experiment String), ``subscribe``
(prints the first JointState it receives as JSON, then exits).
"""

import json
import sys
import threading

from frf_ident import middleware as mw


def main(mode: str) -> None:
    JointState = mw.msg('sensor_msgs/msg/JointState')
    Header = mw.msg('std_msgs/msg/Header')
    Time = mw.msg('builtin_interfaces/msg/Time')
    node = mw.create_node(f'mw_peer_{mode}')
    stop = threading.Event()
    if mode == 'publish':
        js_pub = node.create_publisher(JointState, '/joint_states', mw.qos_default())
        cmd_pub = node.create_publisher(mw.msg('std_msgs/msg/Float64MultiArray'),
                                        '/effort_controller/commands', mw.qos_default())
        Layout = mw.msg('std_msgs/msg/MultiArrayLayout')
        Dim = mw.msg('std_msgs/msg/MultiArrayDimension')
        count = [0]

        def tick() -> None:
            count[0] += 1
            js_pub.publish(JointState(
                header=Header(stamp=Time(sec=count[0], nanosec=123), frame_id='base'),
                name=['joint1', 'joint2'], position=[0.5, -1.25], velocity=[1e-3, 2.0],
                effort=[float(count[0]), 7.0]))
            cmd_pub.publish(mw.msg('std_msgs/msg/Float64MultiArray')(
                layout=Layout(dim=[Dim(label='joints', size=2, stride=2)], data_offset=0),
                data=[3.5, -4.0]))

        node.create_timer(0.01, tick)
    elif mode == 'service':
        calls = [0]

        def handle(request, response):
            calls[0] += 1
            response.success = True
            response.message = f'iteration {calls[0]} done'
            return response

        node.create_service(mw.srv('std_srvs/srv/Trigger'), '/frf/run_iteration', handle)
    elif mode == 'latched':
        pub = node.create_publisher(mw.msg('std_msgs/msg/String'), '/frf/experiment',
                                    mw.qos_transient_local())
        for i in range(3):
            pub.publish(mw.msg('std_msgs/msg/String')(data=json.dumps({'segment': i})))
    elif mode == 'subscribe':
        def received(msg) -> None:
            print(json.dumps({'name': list(msg.name), 'position': list(msg.position),
                              'sec': msg.header.stamp.sec}), flush=True)
            stop.set()

        node.create_subscription(JointState, '/joint_states', received, mw.qos_default())
    else:
        raise SystemExit(f'unknown {mode=}')
    print('ready', flush=True)
    if mode != 'subscribe':
        threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    mw.spin(node, stop)
    mw.shutdown()


if __name__ == '__main__':
    main(sys.argv[1])
