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
Round-trip benchmark of the Cyclone DDS backend between two processes on loopback.

The ping is a ``std_msgs/Float64MultiArray`` (like a torque command) and the pong a
``sensor_msgs/JointState`` (like the plant's answer), i.e. one lockstep-simulation step.
``make bench`` compares the node graph against this plain-DDS figure.

Run: ``python -m benchmarks.pingpong [-n N]``.
"""

import argparse
import os
from pathlib import Path
import subprocess
import sys
import threading
import time
from typing import Any, Optional

_CONFIG = Path(__file__).resolve().parents[1] / 'config' / 'cyclonedds-localhost.xml'
_N_JOINTS = 6


def loopback_env(env: Optional[dict[str, str]] = None) -> dict[str, str]:
    """``env`` (default os.environ) forced to localhost-only discovery and the DDS backend."""
    out = dict(os.environ if env is None else env)
    out['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    out['FRF_IDENT_MIDDLEWARE'] = 'dds'
    if not out.get('CYCLONEDDS_URI') and _CONFIG.is_file():
        out['CYCLONEDDS_URI'] = _CONFIG.as_uri()
    return out


def _topics(tag: str) -> tuple[str, str]:
    return f'/frf_pingpong_{tag}/ping', f'/frf_pingpong_{tag}/pong'


def _pong(tag: str) -> None:
    """Answer every ping with a JointState carrying the ping's data, until stdin closes."""
    from frf_ident.middleware import dds_backend as dds, ros_types as rt
    ping_topic, pong_topic = _topics(tag)
    node = dds.create_node(f'frf_pong_{tag}')
    pub = node.create_publisher(rt.JointState, pong_topic, 10)
    names = [f'joint{i + 1}' for i in range(_N_JOINTS)]

    def answer(ping: rt.Float64MultiArray) -> None:
        pub.publish(rt.JointState(header=rt.Header(stamp=node.get_clock().now().to_msg()),
                                  name=names, position=ping.data, velocity=ping.data,
                                  effort=ping.data))

    node.create_subscription(rt.Float64MultiArray, ping_topic, answer, 10)
    stop = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    print('ready', flush=True)
    dds.spin(node, stop)
    dds.shutdown()


def dds_pingpong(n: int = 2000, timeout_sec: float = 30.0) -> float:
    """
    Round trips per second of ping/pong over Cyclone DDS between this and a child process.

    The child gets the loopback environment of :func:`loopback_env`; this process must already
    run with it (or be about to create its first participant with ROS_AUTOMATIC_DISCOVERY_RANGE
    set), so no packet leaves loopback.
    """
    if n < 1:
        raise ValueError(f'need at least one round trip, got {n=}')
    os.environ.update({k: v for k, v in loopback_env().items()
                       if k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'CYCLONEDDS_URI')})
    from frf_ident.middleware import dds_backend as dds, ros_types as rt
    tag = f'{os.getpid()}_{time.monotonic_ns() % 1_000_000}'
    ping_topic, pong_topic = _topics(tag)
    child = subprocess.Popen(
        [sys.executable, '-m', 'benchmarks.pingpong', '--pong', tag],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=loopback_env(), text=True)
    try:
        if child.stdout.readline().strip() != 'ready':
            raise RuntimeError(f'pong process failed to start: {child.args=}')
        node = dds.create_node(f'frf_ping_{tag}')
        replies: list[float] = []
        node.create_subscription(rt.JointState, pong_topic,
                                 lambda m: replies.append(m.position[0]), 10)
        pub = node.create_publisher(rt.Float64MultiArray, ping_topic, 10)
        deadline = time.monotonic() + timeout_sec
        while pub.get_subscription_count() == 0 or not replies:  # matched both ways
            if time.monotonic() > deadline:
                raise TimeoutError(f'no pong within {timeout_sec=}: discovery failed?')
            pub.publish(rt.Float64MultiArray(data=[-1.0] * _N_JOINTS))
            node.spin_once(0.05)
        node.spin_once(0.05)
        replies.clear()
        start = time.perf_counter()
        for i in range(n):
            pub.publish(rt.Float64MultiArray(data=[float(i)] * _N_JOINTS))
            while not replies or replies[-1] != float(i):
                if time.monotonic() > deadline:
                    raise TimeoutError(f'pong {i} of {n=} missing after {timeout_sec=}')
                node.spin_once(1.0)
        rate = n / (time.perf_counter() - start)
        node.destroy_node()
        return rate
    finally:
        child.stdin.close()
        try:
            child.wait(timeout=10)
        except subprocess.TimeoutExpired:
            child.kill()


def _mw_pong(tag: str) -> None:
    """As :func:`_pong`, through frf_ident.middleware (backend from FRF_IDENT_MIDDLEWARE)."""
    from frf_ident import middleware as mw
    ping_topic, pong_topic = _topics(tag)
    JointState = mw.msg('sensor_msgs/msg/JointState')
    F64 = mw.msg('std_msgs/msg/Float64MultiArray')
    node = mw.create_node(f'frf_pong_{tag}')
    pub = node.create_publisher(JointState, pong_topic, mw.qos_default(10))
    names = [f'joint{i + 1}' for i in range(_N_JOINTS)]

    def answer(ping: Any) -> None:
        d = list(ping.data)
        pub.publish(JointState(name=names, position=d, velocity=d, effort=d))

    node.create_subscription(F64, ping_topic, answer, mw.qos_default(10))
    stop = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    print('ready', flush=True)
    mw.spin(node, stop)
    mw.shutdown()


def _mw_ping(tag: str, n: int, timeout_sec: float) -> None:
    """Ping side in its own process; prints the round trips per second."""
    from frf_ident import middleware as mw
    ping_topic, pong_topic = _topics(tag)
    JointState = mw.msg('sensor_msgs/msg/JointState')
    F64 = mw.msg('std_msgs/msg/Float64MultiArray')
    node = mw.create_node(f'frf_ping_{tag}')
    replies: list[float] = []
    node.create_subscription(JointState, pong_topic, lambda m: replies.append(m.position[0]),
                             mw.qos_default(10))
    pub = node.create_publisher(F64, ping_topic, mw.qos_default(10))
    deadline = time.monotonic() + timeout_sec
    while pub.get_subscription_count() == 0 or not replies:
        if time.monotonic() > deadline:
            raise TimeoutError(f'no pong within {timeout_sec=}')
        pub.publish(F64(data=[-1.0] * _N_JOINTS))
        mw.spin_once(node, 0.05)
    mw.spin_once(node, 0.05)
    replies.clear()
    start = time.perf_counter()
    for i in range(n):
        pub.publish(F64(data=[float(i)] * _N_JOINTS))
        while not replies or replies[-1] != float(i):
            if time.monotonic() > deadline:
                raise TimeoutError(f'pong {i} of {n=} missing')
            mw.spin_once(node, 1.0)
    print(f'rate {n / (time.perf_counter() - start)}', flush=True)
    mw.shutdown()


def pingpong(backend: str, n: int = 2000, timeout_sec: float = 60.0) -> float:
    """
    Round trips per second between two processes on ``backend`` ('rclpy' or 'dds').

    Parameters
    ----------
    backend
        Frf_ident middleware backend of both processes.
    n
        Round trips.
    timeout_sec
        Give up after this long.

    Returns
    -------
    float
        Round trips per second (the same messages as one lockstep step).

    """
    env = loopback_env()
    env['FRF_IDENT_MIDDLEWARE'] = backend
    env['ROS_DOMAIN_ID'] = os.environ.get('FRF_BENCH_DOMAIN', env.get('ROS_DOMAIN_ID', '0'))
    tag = f'{os.getpid()}_{time.monotonic_ns() % 1_000_000}'
    pong = subprocess.Popen([sys.executable, '-m', 'benchmarks.pingpong', '--mw-pong', tag],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env, text=True)
    try:
        if pong.stdout.readline().strip() != 'ready':
            raise RuntimeError('pong process failed to start')
        out = subprocess.run([sys.executable, '-m', 'benchmarks.pingpong', '--mw-ping', tag,
                              '-n', str(n)], env=env, capture_output=True, text=True,
                             timeout=timeout_sec + 30, check=True).stdout
        return float(out.split('rate ')[1].split()[0])
    finally:
        pong.stdin.close()
        try:
            pong.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pong.kill()


def main(argv: Optional[list[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('-n', type=int, default=2000, help='round trips (default 2000)')
    parser.add_argument('--pong', metavar='TAG', help=argparse.SUPPRESS)
    parser.add_argument('--mw-pong', metavar='TAG', help=argparse.SUPPRESS)
    parser.add_argument('--mw-ping', metavar='TAG', help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.pong:
        _pong(args.pong)
        return
    if args.mw_pong:
        _mw_pong(args.mw_pong)
        return
    if args.mw_ping:
        _mw_ping(args.mw_ping, args.n, 60.0)
        return
    rate = dds_pingpong(args.n)
    print(f'dds ping-pong: {rate:.0f} round trips/s ({1e6 / rate:.0f} us per round trip)')


if __name__ == '__main__':
    main()
