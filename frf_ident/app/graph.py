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
Start the node graph as separate OS processes and drive an identification.

:class:`Graph` writes a ROS parameter file, starts plant, controller, excitation and estimator
as ``python -m frf_ident.nodes.<node> --ros-args --params-file F`` with a loopback-only
environment (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, CYCLONEDDS_URI =
config/cyclonedds-localhost.xml), waits until every node reports ready, then drives the
identification from a driver process (``/frf/run_multisine``, then ``/frf/run_iteration`` until
converged or max_iterations; each service answers once the plan is checked and the driver
waits for the run's ``finished`` event on /frf/progress) and stops the graph with SIGINT (the
estimator drains and finalises the bag).

Middleware: rclpy when ROS 2 is sourced, else the Cyclone DDS backend (``middleware=`` or
FRF_IDENT_MIDDLEWARE choose). Domain: ``domain_id=``, else ROS_DOMAIN_ID when set (so
``ros2 topic echo`` in the user's shell sees the graph), else a random one in 100..149.

    bag, results = run_graph('out/run', multisine=MultisineConfig(...), chirp=ChirpConfig(...))
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import os
from pathlib import Path
import random
import signal
import subprocess
import sys
import threading
import time
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.share import share_dir, SOURCE_ROOT
import numpy as np
import yaml

_log = logging.getLogger(__name__)

#: how long a node may take to come up (import numpy/scipy/numba, compile the plant) before
#: the graph gives up: a watchdog for a node that hangs, not a speed goal. On 2 shared cores
#: at load average 20 the plant node took more than 60 s (the former limit: `make demo`
#: failed twice)
START_TIMEOUT_S = 300.0
#: free-running: the PI in its own node, as a robot's velocity loop
NODES = ('plant_node', 'controller_node', 'excitation_node', 'estimator_node')
#: lockstep simulation: the plant hosts the PI (``velocity_control``), as ros2_control hosts its
#: controllers beside the hardware, so no plant -> controller -> plant round trip per sample
LOCKSTEP_NODES = ('plant_node', 'excitation_node', 'estimator_node')


#: random domains (when neither domain_id nor ROS_DOMAIN_ID is given) come from this range
RANDOM_DOMAINS = (100, 149)
#: exit status of the driver when the excitation node refused a run (unsafe or invalid
#: settings: the user's to change); Graph.drive raises FrfIdentInputError for it (argparse
#: uses 2)
REFUSED = 3


def default_domain_id(env: Optional[dict] = None) -> int:
    """
    ROS_DOMAIN_ID of ``env`` (default os.environ) when set, else a random one.

    Parameters
    ----------
    env
        Environment to read.

    Returns
    -------
    int
        The domain id.

    """
    value = (os.environ if env is None else env).get('ROS_DOMAIN_ID', '').strip()
    return int(value) if value else random.randint(*RANDOM_DOMAINS)


def default_middleware() -> str:
    """FRF_IDENT_MIDDLEWARE when set, else 'rclpy' when ROS 2 is sourced, else 'dds'."""
    forced = os.environ.get(mw.ENV_BACKEND, '').strip().lower()
    if forced:
        return forced
    import importlib.util
    return 'rclpy' if importlib.util.find_spec('rclpy') is not None else 'dds'


def graph_env(domain_id: int, base: Optional[dict] = None,
              middleware: Optional[str] = None) -> dict[str, str]:
    """
    Environment of the node processes: loopback, ``domain_id``, the chosen middleware.

    Parameters
    ----------
    domain_id
        ROS_DOMAIN_ID.
    base
        Environment to start from (default os.environ).
    middleware
        'rclpy' or 'dds' (default :func:`default_middleware`).

    Returns
    -------
    dict
        The environment.

    """
    env = dict(os.environ if base is None else base)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env[mw.ENV_BACKEND] = middleware or default_middleware()
    env.setdefault('RMW_IMPLEMENTATION', 'rmw_cyclonedds_cpp')
    env['ROS_DOMAIN_ID'] = str(int(domain_id))
    cfg = share_dir() / 'config' / 'cyclonedds-localhost.xml'
    if cfg.is_file():
        env['CYCLONEDDS_URI'] = cfg.as_uri()
    env['PYTHONPATH'] = os.pathsep.join([str(SOURCE_ROOT)] + [p for p in env.get(
        'PYTHONPATH', '').split(os.pathsep) if p])
    env['PYTHONUNBUFFERED'] = '1'
    return env


def _cfg_params(prefix: str, cfg: Any) -> dict[str, Any]:
    out = {}
    for f in dataclasses.fields(cfg):
        v = getattr(cfg, f.name)
        if isinstance(v, np.ndarray):
            v = v.reshape(-1).tolist()
        elif isinstance(v, np.generic):
            v = v.item()
        out[f'{prefix}.{f.name}'] = v
    return out


class Graph:
    """The four node processes on one private ROS domain."""

    def __init__(self, out_dir: str | Path, *, model: Optional[str | Path] = None,
                 robot: Optional[str | Path] = None, multisine: Any = None, chirp: Any = None,
                 lockstep: bool = True, domain_id: Optional[int] = None,
                 params: Optional[dict[str, dict[str, Any]]] = None,
                 log: Any = None, nodes: Optional[Sequence[str]] = None,
                 middleware: Optional[str | dict[str, str]] = None) -> None:
        self.nodes = tuple(nodes if nodes is not None else
                           (LOCKSTEP_NODES if lockstep else NODES))
        self.out = Path(out_dir)
        self.out.mkdir(parents=True, exist_ok=True)
        self.bag = self.out / 'bag'
        self.frf_dir = self.out / 'frf_live'
        self.domain_id = domain_id if domain_id is not None else default_domain_id()
        per_node = middleware if isinstance(middleware, dict) else {}
        self.env = graph_env(self.domain_id, middleware=None if per_node else middleware)
        self.middleware = self.env[mw.ENV_BACKEND]
        #: backend of each node process (a dict ``middleware`` mixes rclpy and DDS nodes)
        self.node_middleware = {n: per_node.get(n, self.middleware) for n in self.nodes}
        self.robot = str(robot or model or '')
        self.say = log or (lambda m: None)
        # lockstep is the simulation's mode; free-running runs on wall time like a robot
        common: dict[str, Any] = {'use_sim_time': bool(lockstep), 'lockstep': bool(lockstep),
                                  'model': self.robot}
        # a simulated plant: no operator arming, also free-running (``params`` may ask for it)
        exc: dict[str, Any] = {'arming': 'off'}
        if multisine is not None:
            exc.update(_cfg_params('multisine', multisine))
        if chirp is not None:
            exc.update(_cfg_params('chirp', chirp))
        self.max_iterations = int(chirp.max_iterations) if chirp is not None else 0
        self.run_multisine = multisine is not None
        plant = {'velocity_control': bool(lockstep and 'controller_node' not in self.nodes)}
        sections = {'/**': common, 'plant_node': plant, 'controller_node': {},
                    'excitation_node': exc,
                    'estimator_node': {'bag': str(self.bag), 'output_dir': str(self.frf_dir)}}
        for name, extra in (params or {}).items():
            sections.setdefault(name, {}).update(extra)
        self.params_file = self.out / 'frf_ident_params.yaml'
        self.params_file.write_text(yaml.safe_dump(
            {k: {'ros__parameters': v} for k, v in sections.items()}, sort_keys=False))
        self.procs: dict[str, subprocess.Popen] = {}
        self.logs: dict[str, list[str]] = {}
        self._ready: dict[str, threading.Event] = {}

    def _reader(self, name: str, proc: subprocess.Popen) -> None:
        for line in proc.stdout:
            self.logs[name].append(line.rstrip())
            if line.startswith(mw.READY):
                self._ready[name].set()

    def start(self, timeout_s: float = START_TIMEOUT_S) -> 'Graph':
        if self.bag.exists():
            raise FileExistsError(f'{self.bag} exists; refusing to overwrite recorded data')
        for name in self.nodes:
            cmd = [sys.executable, '-m', f'frf_ident.nodes.{name}', '--ros-args',
                   '--params-file', str(self.params_file)]
            errf = open(self.out / f'{name}.log', 'w')
            env = dict(self.env, **{mw.ENV_BACKEND: self.node_middleware[name]})
            proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=errf,
                                    text=True, cwd=str(SOURCE_ROOT))
            self.procs[name], self.logs[name] = proc, []
            self._ready[name] = threading.Event()
            threading.Thread(target=self._reader, args=(name, proc), daemon=True).start()
        deadline = time.monotonic() + timeout_s
        for name, ev in self._ready.items():
            while not ev.wait(0.1):
                if self.procs[name].poll() is not None:
                    self.stop()
                    raise RuntimeError(f'{name} exited with {self.procs[name].returncode}; see '
                                       f'{self.out / (name + ".log")}')
                if time.monotonic() > deadline:
                    self.stop()
                    raise TimeoutError(f'{name} not ready within {timeout_s} s')
        self.say(f'graph up on ROS_DOMAIN_ID={self.domain_id}: ' + ', '.join(
            f'{n} ({self.node_middleware[n]})' for n in self.nodes))
        return self

    def driver(self, *, multisine: Optional[bool] = None, iterations: Optional[int] = None,
               timeout_s: float = 600.0) -> subprocess.Popen:
        cmd = [sys.executable, '-m', 'frf_ident.app.graph', 'drive',
               '--iterations', str(self.max_iterations if iterations is None else iterations),
               '--timeout', str(timeout_s)]
        if multisine if multisine is not None else self.run_multisine:
            cmd.append('--multisine')
        return subprocess.Popen(cmd, env=self.env, stdout=subprocess.PIPE, text=True,
                                stderr=open(self.out / 'driver.log', 'w'), cwd=str(SOURCE_ROOT))

    def drive(self, **kw: Any) -> dict:
        """
        Run the identification (blocking); returns the driver's results.

        Raises FrfIdentInputError when the excitation node refused a run (its error, e.g. a
        torque predicted beyond 0.95 of a limit), RuntimeError when a run failed or aborted.
        """
        from frf_ident.app.console import LiveLine
        proc = self.driver(**kw)
        results: dict[str, Any] = {'iterations': []}
        status = LiveLine(self.say)
        for line in proc.stdout:
            if line.startswith('FRF_ESTIMATE '):
                status.update(json.loads(line[len('FRF_ESTIMATE '):])['line'])
            elif line.startswith('FRF_RESULT '):
                status.end()
                d = json.loads(line[len('FRF_RESULT '):])
                if d.get('kind') == 'multisine':
                    results['multisine'] = d
                else:
                    results['iterations'].append(d)
                _log.debug('driver: %s', json.dumps(d))
                self.say(result_line(d))
        rc = proc.wait()
        last = (results['iterations'] or [results.get('multisine')])[-1]
        if rc == REFUSED and last and last.get('reply', {}).get('refused'):
            what = 'multisine' if last['kind'] == 'multisine' else 'chirp iteration'
            error = last['reply']['error']
            raise FrfIdentInputError(f'excitation_node refused the {what}: {error}')
        if rc != 0:
            raise RuntimeError(f'graph driver failed ({rc}): {self.failure(last)}; see '
                               f'{self.out / "driver.log"}')
        return results

    def failure(self, last: Optional[dict]) -> str:
        """Return why the driver failed: its last run's error, else its log's last line."""
        if last and last.get('reply', {}).get('error'):
            return f"{last['kind']} {last['reply']['error']}"
        log = self.out / 'driver.log'
        lines = log.read_text(errors='replace').strip().splitlines() if log.exists() else []
        return lines[-1] if lines else 'no result and an empty driver.log'

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        self.procs[name].send_signal(sig)

    def stop(self, timeout_s: float = 60.0) -> Path:
        """SIGINT every node (estimator last), wait; returns the bag path."""
        order = ('excitation_node', 'controller_node', 'plant_node', 'estimator_node')
        for name in order:
            p = self.procs.get(name)
            if p is None or p.poll() is not None:
                continue
            p.send_signal(signal.SIGINT)
            try:
                p.wait(timeout_s)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        return self.bag

    def __enter__(self) -> 'Graph':
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()


def run_graph(out_dir: str | Path, *, model: Optional[str | Path] = None,
              robot: Optional[str | Path] = None, multisine: Any = None, chirp: Any = None,
              domain_id: Optional[int] = None, log: Any = None,
              params: Optional[dict[str, dict[str, Any]]] = None,
              middleware: Optional[str] = None) -> tuple[Path, dict]:
    """Full identification over the node graph; returns (bag path, driver results)."""
    g = Graph(out_dir, model=model, robot=robot, multisine=multisine, chirp=chirp,
              domain_id=domain_id, log=log, params=params, middleware=middleware)
    g.start()
    try:
        results = g.drive()
    finally:
        bag = g.stop()
    results['frf_live'] = str(g.frf_dir)
    return bag, results


def result_line(d: dict) -> str:
    """
    Return one line for a person from the driver's FRF_RESULT of one run.

    Parameters
    ----------
    d : dict
        ``{'kind', 'success', 'reply'}`` as the driver prints it.

    Returns
    -------
    str
        E.g. ``iteration run 3: chirp iteration 2, error to u_des 0.41 / 0.38 / 0.52 dB,
        converged; 20.0 s of experiment at 2,310 steps/s``.

    """
    r = d.get('reply') or {}
    head = f"{d.get('kind')} run {r.get('run', '?')}"
    if not d.get('success'):
        return f"{head}: failed: {r.get('error', 'no reason given')}"
    found = []
    if 'iteration' in r:
        found.append(f"chirp iteration {r['iteration']}")
    if 'error_db' in r:
        errs = np.atleast_1d(np.asarray(r['error_db'], dtype=float))
        found.append('error to u_des ' + ' / '.join(f'{e:.2f}' for e in errs) + ' dB')
    if 'converged' in r:
        found.append('converged' if r['converged'] else 'not converged')
    timing = f"{r.get('experiment_time_s', 0.0):.1f} s of experiment"
    if 'steps_per_s' in r:
        timing += f" at {r['steps_per_s']:,.0f} steps/s"
    return f"{head}: {', '.join(found + [timing])}"


_EMIT = threading.Lock()


def _emit(line: str) -> None:
    """Write one whole line to stdout (the driver writes from two threads)."""
    with _EMIT:
        sys.stdout.write(line + '\n')
        sys.stdout.flush()


class _Waiter:
    """
    The driver's view of /frf/progress: the ``finished`` event of each run.

    Each live ``estimate`` event goes to stdout as ``FRF_ESTIMATE {json}`` (Graph.drive
    shows its status line).
    """

    def __init__(self, node: Any) -> None:
        self.cond = threading.Condition()
        self.finished: dict[int, dict] = {}
        node.create_subscription(mw.msg('std_msgs/msg/String'), '/frf/progress', self._on,
                                 mw.qos_transient_local(10))

    def _on(self, msg: Any) -> None:
        d = json.loads(msg.data)
        if d.get('event') == 'estimate' and d.get('line'):
            _emit('FRF_ESTIMATE ' + json.dumps(d))
        if d.get('event') == 'finished':
            with self.cond:
                self.finished[int(d['run'])] = d
                self.cond.notify_all()

    def wait(self, run_id: int, timeout_s: float) -> dict:
        with self.cond:
            if not self.cond.wait_for(lambda: run_id in self.finished, timeout_s):
                raise TimeoutError(f'run {run_id} did not finish within {timeout_s} s')
            return self.finished[run_id]


def _run(client: Any, Trigger: Any, waiter: _Waiter, timeout_s: float) -> tuple[bool, dict]:
    """Start a procedure (the service answers once it is planned) and wait for its end."""
    deadline = time.monotonic() + 10.0
    while True:
        rep = client.call(Trigger.Request(), 30.0)
        ack = json.loads(rep.message)
        if rep.success or time.monotonic() > deadline or 'joint_states' not in ack.get(
                'error', ''):
            break
        time.sleep(0.2)       # the plant's first joint state has not arrived yet
    if not rep.success:
        return False, ack
    end = waiter.wait(int(ack['run']), timeout_s)
    if not end.get('success'):
        return False, {'error': end.get('error', 'failed'), 'run': ack['run']}
    return True, dict(end['result'], run=ack['run'])


def _drive(args: argparse.Namespace) -> int:
    """Driver process: call the services in order, print one FRF_RESULT line per run."""
    mw.init([])
    node = mw.create_node('frf_graph_driver')
    stop = threading.Event()
    spinner = threading.Thread(target=mw.spin, args=(node, stop), daemon=True)
    waiter = _Waiter(node)
    spinner.start()
    Trigger = mw.srv('std_srvs/srv/Trigger')
    cl_ms = node.create_client(Trigger, '/frf/run_multisine')
    cl_it = node.create_client(Trigger, '/frf/run_iteration')
    try:
        for cl in (cl_ms, cl_it):
            if not cl.wait_for_service(30.0):
                raise TimeoutError(f'{cl.service_name} not available')
        time.sleep(0.5)   # the plant re-sends its joint state: every recorder has sample 0
        if args.multisine:
            ok, reply = _run(cl_ms, Trigger, waiter, args.timeout)
            _emit('FRF_RESULT ' + json.dumps({'kind': 'multisine', 'success': ok,
                                             'reply': reply}))
            if not ok:
                return REFUSED if reply.get('refused') else 1
        for _ in range(args.iterations):
            ok, reply = _run(cl_it, Trigger, waiter, args.timeout)
            _emit('FRF_RESULT ' + json.dumps({'kind': 'iteration', 'success': ok,
                                             'reply': reply}))
            if not ok:
                return REFUSED if reply.get('refused') else 1
            if reply.get('converged'):
                break
        return 0
    finally:
        stop.set()
        spinner.join(2.0)
        mw.shutdown()


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest='cmd', required=True)
    d = sub.add_parser('drive')
    d.add_argument('--multisine', action='store_true')
    d.add_argument('--iterations', type=int, default=0)
    d.add_argument('--timeout', type=float, default=600.0)
    args = p.parse_args(argv)
    return _drive(args)


if __name__ == '__main__':
    raise SystemExit(main())
