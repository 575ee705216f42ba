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
"""`frf-ident identify` -> bag -> `frf-ident estimate`: the bag carries everything."""
import json

from frf_ident.bag import read_recording
from frf_ident.cli import main
from frf_ident.cli.identify import identification_config
from frf_ident.cli.main import build_parser
from frf_ident.core.estimation.described import estimate_recording
from frf_ident.core.simulation.runner import run_identification
from frf_ident.io.model_file import load_model, load_plant
import numpy as np
import pytest
import yaml

ARGS = ['--realisations', '2', '--periods', '2', '--resolution', '0.5',
        '--chirp-duration', '8', '--max-iterations', '2']


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    out = tmp_path_factory.mktemp('id') / 'bag'
    assert main(['identify', '--out', str(out), *ARGS]) == 0
    return out


def test_bag_is_rosbag2_mcap_v9_readable_by_rosbags_and_mcap(bag):
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['version'] == 9 and meta['storage_identifier'] == 'mcap'
    topics = {t['topic_metadata']['name']: t['topic_metadata']['type']
              for t in meta['topics_with_message_count']}
    assert topics['/joint_states'] == 'sensor_msgs/msg/JointState'
    assert topics['/velocity_controller/commands'] == 'std_msgs/msg/Float64MultiArray'
    assert topics['/effort_controller/commands'] == 'std_msgs/msg/Float64MultiArray'
    assert topics['/frf/excitation'] == 'sensor_msgs/msg/JointState'
    assert topics['/frf/experiment'] == 'std_msgs/msg/String'
    from rosbags.highlevel import AnyReader
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == '/frf/experiment']
        texts = [reader.deserialize(raw, c.msgtype).data
                 for c, _, raw in reader.messages(connections=conns)]
    events = [json.loads(t)['event'] for t in texts]
    assert events.count('start') == events.count('end') > 0
    from mcap_ros2.reader import read_ros2_messages
    mcap_file = next(bag.glob('*.mcap'))
    n = 0
    for m in read_ros2_messages(str(mcap_file), topics=['/joint_states']):
        assert len(m.ros_msg.position) == 3
        n += 1
        if n > 100:
            break
    assert n > 100


def test_estimate_from_bag_equals_in_memory_run(bag, tmp_path):
    model, _, ctrl = load_model(None)
    parser_args = build_parser().parse_args(['identify', '--out', str(bag), *ARGS])
    rec = run_identification(load_plant(None, model), ctrl, identification_config(parser_args))
    mem = estimate_recording(rec)
    from_bag = estimate_recording(read_recording(bag)[0])
    assert set(mem) == set(from_bag)
    for k in mem:
        assert np.allclose(from_bag[k].response, mem[k].response, rtol=1e-12, atol=0), k
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'est')]) == 0
    doc = json.loads((tmp_path / 'est' / 'frf.json').read_text())
    assert np.asarray(doc['re']).shape == (3, 3, len(doc['freq_hz']))
    assert np.allclose(np.asarray(doc['re']) + 1j * np.asarray(doc['im']),
                       mem['multisine'].response, rtol=1e-12)
    assert (tmp_path / 'est' / 'bode.png').stat().st_size > 10_000


def test_identify_refuses_existing_bag_and_bad_model(bag, tmp_path, capsys):
    before = sorted(p.stat().st_mtime_ns for p in bag.iterdir())
    assert main(['identify', '--out', str(bag), *ARGS]) == 2
    assert sorted(p.stat().st_mtime_ns for p in bag.iterdir()) == before
    err = capsys.readouterr().err
    assert 'already exists' in err and len(err.strip().splitlines()) == 1
    bad = tmp_path / 'm.yaml'
    bad.write_text('frf_ident_model: 1\naxes:\n  - {name: j, motor_inertia: -3}\n')
    assert main(['identify', '--model', str(bad), '--out', str(tmp_path / 'b')]) == 2
    err = capsys.readouterr().err
    assert 'motor_inertia=-3' in err and len(err.strip().splitlines()) == 1
    assert main(['identify', '--model', str(tmp_path / 'nope.yaml'),
                 '--out', str(tmp_path / 'b')]) == 2
    assert main(['identify', '--plant', 'no_such_mod:X', '--out', str(tmp_path / 'b')]) == 2


def test_identify_refuses_torque_limits_below_the_excitation(tmp_path, capsys):
    """An unsafe combination (limit below the chirp's desired torque) is input: exit 2."""
    from frf_ident.core.model.schema import default_model_dict
    model = default_model_dict()
    model['axes'][1]['torque_limit'] = 120.0
    path = tmp_path / 'low.yaml'
    path.write_text(yaml.safe_dump(model))
    out = tmp_path / 'b'
    assert main(['identify', '--model', str(path), '--out', str(out), *ARGS,
                 '--procedures', 'chirp']) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'torque limits [300.0, 120.0, 300.0]' in err
    assert 'Traceback' not in err and not out.exists()


def test_identify_refuses_a_multisine_predicted_to_need_95_percent_of_a_limit(tmp_path, capsys):
    """
    Joint 2's limit at 200 N m: the chirp's 150 N m fits, the multisine needs 198 N m.

    The dry run on the model predicts it (the limit itself is not reached, so the run would
    not even have saturated): refused with one line naming the joint and the remedy, nothing
    recorded; with the remedy applied the run goes ahead and stays below 0.95 of the limit.
    """
    from frf_ident.core.model.schema import default_model_dict
    model = default_model_dict()
    model['axes'][1]['torque_limit'] = 200.0
    path = tmp_path / 'tight.yaml'
    path.write_text(yaml.safe_dump(model))
    out = tmp_path / 'b'
    assert main(['identify', '--model', str(path), '--out', str(out), *ARGS]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'multisine: the peak torque predicted' in err
    peak = float(err.split('joint_2 ')[1].split(' of 200 N m')[0])
    assert 190.0 <= peak < 200.0 and not out.exists()
    assert 'amplitude_ratio (0.75) or position_bound_deg (4' in err
    # the remedy it names: half the travel, half the velocities; the run then stays below
    assert main(['identify', '--model', str(path), '--out', str(out), *ARGS,
                 '--procedures', 'multisine', '--position-bound', '2']) == 0
    rec, _ = read_recording(out)
    print(f'predicted {peak} N m refused; at --position-bound 2: measured peak '
          f'{np.abs(rec.effort[:, 1]).max():.1f} N m')
    assert np.abs(rec.effort[:, 1]).max() < 0.95 * 200.0


def test_identify_checks_every_plan_before_anything_runs(tmp_path):
    """Joint 1's limit at 100 N m refuses the chirp: before the multisine, not after it."""
    from frf_ident.app.identify import run_identify
    from frf_ident.core.model.schema import default_model_dict
    from frf_ident.errors import SafetyError
    model = default_model_dict()
    model['axes'][0]['torque_limit'] = 100.0
    path = tmp_path / 'j1.yaml'
    path.write_text(yaml.safe_dump(model))
    lines = []
    cfg = identification_config(build_parser().parse_args(
        ['identify', '--out', str(tmp_path / 'b'), *ARGS]))
    with pytest.raises(SafetyError, match=r'reach the torque limits \[100.0, 400.0, 300.0\]'):
        run_identify(path, None, cfg, tmp_path / 'b', progress=lines.append)
    assert lines == [] and not (tmp_path / 'b').exists()
