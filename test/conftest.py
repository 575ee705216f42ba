"""Shared test setup: every DDS participant stays on loopback (docs/CONTRACT.md §2)."""
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / 'shared' / 'data'

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('CYCLONEDDS_URI', (ROOT / 'config' / 'cyclonedds-localhost.xml').as_uri())
os.environ.setdefault('MPLBACKEND', 'Agg')
