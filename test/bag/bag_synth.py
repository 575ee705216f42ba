"""Synthetic recordings for the bag tests (3 joints of sines, built with numpy)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from frf_ident.core.recording import Recording, Segment

JOINTS = ['joint_1', 'joint_2', 'joint_3']
FREQS = np.array([0.7, 1.3, 2.1])  # Hz


def make_recording(seconds: float = 5.0, fs: float = 1000.0, t0: float = 0.0) -> Recording:
    """3 joints of sines; reference NaN before 0.5 s and in a short idle block."""
    n = int(round(seconds * fs))
    t = t0 + np.arange(n) / fs
    w = 2 * np.pi * FREQS
    pos = np.sin(np.outer(t, w)) / w
    vel = np.cos(np.outer(t, w))
    eff = 3.0 * np.sin(np.outer(t, w) + 0.3)
    ref = vel * 1.01
    ref[: int(0.5 * fs)] = np.nan
    ref[int(2.0 * fs):int(2.1 * fs)] = np.nan
    exc = 0.2 * vel
    exc[: int(0.5 * fs)] = np.nan
    segs = [Segment(t0 + 0.5, t0 + 2.0, {'design': 'multisine', 'realisation': 0, 'experiment': 0,
                                         'freq_hz': [1.0, 2.0, 3.0]}),
            Segment(t0 + 2.1, t0 + seconds - 0.5, {'design': 'chirp', 'iteration': 1})]
    meta = {'seed': 7, 'model': {'axes': 3}, 'note': 'synthetic'}
    return Recording(t, list(JOINTS), pos, vel, eff, ref, exc, segs, meta)


