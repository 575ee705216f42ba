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
Damaged and unfinished bags: what was lost, rewriting them whole, raw message access.

:func:`recovery_report` sums up the scanner's findings (bytes, chunks and messages lost);
:func:`reindex` rewrites a bag cut short or damaged as a complete one (like ``ros2 bag
reindex`` plus recovery); :func:`iter_raw` streams every readable message undecoded.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Iterator

from .collect import iter_batches, scan
from .layout import BagFiles, locate
from .mcapio import Batch, ScanStats


def recovery_report(bag: BagFiles, stats: list[ScanStats], read_counts: dict[str, int],
                    expected: dict[str, int]) -> dict[str, Any]:
    """
    Sum up what a scan of ``bag`` could not read.

    ``complete``, ``bytes_lost``, ``chunks_lost``, ``problems``, ``damaged`` and
    ``messages_lost`` (per topic too when ``expected`` counts are known from metadata.yaml or
    the MCAP summary; topics not read are not counted as lost).
    """
    rec: dict[str, Any] = {
        'complete': all(s.complete for s in stats),
        'bytes_lost': sum(s.bytes_lost for s in stats),
        'chunks_lost': sum(s.chunks_lost for s in stats),
        'problems': [p for s in stats for p in s.problems],
        'metadata_yaml': bag.metadata is not None,
    }
    # a chunk whose CRC or decompression failed loses its messages though every byte was read
    rec['damaged'] = bool(rec['bytes_lost'] or rec['chunks_lost'] or not rec['complete'])
    if expected:
        lost = {t: expected[t] - n for t, n in read_counts.items()
                if expected.get(t, 0) > n}       # topics not read are not lost
        rec['messages_lost'] = sum(lost.values())
        rec['messages_lost_per_topic'] = lost
    elif not rec['complete']:
        rec['messages_lost'] = 'unknown (no summary and no metadata.yaml)'
    else:
        rec['messages_lost'] = 0
    return rec


def reindex(path: str | Path, out: str | Path) -> Path:
    """
    Rewrite a damaged or unfinished bag as a complete one.

    Rewrite a damaged or unfinished bag as a complete one at ``out`` (all readable messages,
    summary, footer and metadata.yaml), like ``ros2 bag reindex`` plus recovery.

    Parameters
    ----------
    path : str or Path
        The damaged bag: rosbag2 directory or a bare .mcap file.
    out : str or Path
        Directory of the new bag (must not exist).

    Returns
    -------
    Path
        ``out``.

    """
    from .recorder import BagRecorder

    bag = locate(path)
    rec = BagRecorder(chunk_bytes=1 << 20, flush_period_s=1e9)
    rec.open(out)
    try:
        def copy(batch: Batch) -> None:
            ch = batch.channel
            for log, a, b in zip(batch.logs, batch.starts, batch.ends):
                rec.write(ch.topic, ch.msgtype, log, batch.buf[a:b])
        scan(bag, None, None, copy)
    finally:
        rec.close()
    return Path(out)


def iter_raw(path: str | Path, topics: set[str] | None = None) -> Iterator[tuple[str, str, int,
                                                                                 bytes]]:
    """
    (topic, type, log_time_ns, cdr) of every readable message, streaming.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory or a bare .mcap file.
    topics : set of str, optional
        Topics to read; default: all.

    Yields
    ------
    tuple of (str, str, int, bytes)
        (topic name, message type, log time in ns, CDR-serialised message bytes), in file
        order.

    """
    bag = locate(path)
    stats: list[ScanStats] = []
    for batch in iter_batches(bag, topics, None, stats):
        ch = batch.channel
        for log, a, b in zip(batch.logs, batch.starts, batch.ends):
            yield ch.topic, ch.msgtype, log, bytes(batch.buf[a:b])


__all__ = ['iter_raw', 'recovery_report', 'reindex']
