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
Summary of a bag (topics, types, counts, time span) like ``ros2 bag info``.

Read from metadata.yaml when present, else from the MCAP summaries, else by scanning the
files (then also reporting what could not be read).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from frf_ident.errors import BagError

from .layout import BagFiles, locate
from .mcapio import McapFormatError, McapScanner, read_summary


def bag_info(path: str | Path) -> dict[str, Any]:
    """
    Topics, types, message counts, start and duration of a bag (like ``ros2 bag info``).

    Uses metadata.yaml when present, else the MCAP summary, else scans the file (then also
    reporting what could not be read).

    Parameters
    ----------
    path : str or Path
        rosbag2 directory or a bare .mcap file.

    Returns
    -------
    dict
        ``path``, ``files``, ``storage``, ``metadata_yaml``, ``message_count``, ``start_s``,
        ``end_s``, ``duration_s`` (s), ``topics`` (list of {``name``, ``type``,
        ``count``}), ``complete`` and ``bytes_lost``; with metadata.yaml also ``version``.

    """
    bag = locate(path)
    if bag.metadata is not None:
        return _info_from_metadata(bag)
    topics: dict[str, dict[str, Any]] = {}
    t0, t1, complete, lost = None, None, True, 0
    for f in bag.files:
        summ = read_summary(f)
        if summ is not None:
            chans, counts, s0, s1 = summ
            for cid, ch in chans.items():
                _add_topic(topics, ch.topic, ch.msgtype, counts.get(cid, 0))
            if counts:
                t0 = s0 if t0 is None else min(t0, s0)
                t1 = s1 if t1 is None else max(t1, s1)
            continue
        scanner = McapScanner(f)
        try:
            for ch, log, _ in scanner.messages():
                _add_topic(topics, ch.topic, ch.msgtype, 1)
                t0 = log if t0 is None else min(t0, log)
                t1 = log if t1 is None else max(t1, log)
        except McapFormatError as exc:
            raise BagError(f'{f}: not a readable MCAP file ({exc})') from None
        complete &= scanner.stats.complete
        lost += scanner.stats.bytes_lost
    return _info_dict(bag, topics, t0 or 0, t1 or 0, complete, lost)


def _add_topic(topics: dict[str, dict[str, Any]], name: str, msgtype: str, n: int) -> None:
    entry = topics.setdefault(name, {'name': name, 'type': msgtype, 'count': 0})
    entry['count'] += n


def _info_dict(bag: BagFiles, topics: dict[str, dict[str, Any]], t0: int, t1: int,
               complete: bool, lost: int) -> dict[str, Any]:
    return {'path': bag.name, 'files': [str(f) for f in bag.files], 'storage': 'mcap',
            'metadata_yaml': bag.metadata is not None,
            'message_count': sum(t['count'] for t in topics.values()),
            'start_s': t0 * 1e-9, 'end_s': t1 * 1e-9, 'duration_s': (t1 - t0) * 1e-9,
            'topics': sorted(topics.values(), key=lambda t: t['name']),
            'complete': complete, 'bytes_lost': lost}


def _info_from_metadata(bag: BagFiles) -> dict[str, Any]:
    m = bag.metadata or {}
    try:
        t0 = int(m['starting_time']['nanoseconds_since_epoch'])
        dur = int(m['duration']['nanoseconds'])
        topics = {}
        for e in m.get('topics_with_message_count') or []:
            tmeta = e['topic_metadata']
            topics[tmeta['name']] = {'name': tmeta['name'], 'type': tmeta['type'],
                                     'count': int(e['message_count'])}
    except (KeyError, TypeError, ValueError) as exc:
        raise BagError(f'{bag.path / "metadata.yaml"}: missing or malformed key {exc}') from None
    d = _info_dict(bag, topics, t0, t0 + dur, True, 0)
    d['version'] = m.get('version')
    d['storage'] = m.get('storage_identifier')
    return d


__all__ = ['bag_info']
