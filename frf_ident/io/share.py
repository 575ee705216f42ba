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
Find the package's data files (config/, launch/).

The installed share directory when the package is installed with colcon (found through
ament_index), else the source checkout.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ['PACKAGE', 'SOURCE_ROOT', 'config_file', 'share_dir']

PACKAGE = 'frf_ident'
#: the checkout root when running from the source tree (setup.py beside the package)
SOURCE_ROOT = Path(__file__).resolve().parents[2]


def share_dir() -> Path:
    """
    Return the directory holding ``config/`` and ``launch/``.

    Returns
    -------
    Path
        ``share/frf_ident`` of the colcon install when ament_index knows the package and this
        module runs from that install; the source checkout otherwise.

    """
    if (SOURCE_ROOT / 'setup.py').is_file() and (SOURCE_ROOT / 'config').is_dir():
        return SOURCE_ROOT
    try:
        from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
    except ImportError:
        return SOURCE_ROOT
    try:
        return Path(get_package_share_directory(PACKAGE))
    except PackageNotFoundError:
        return SOURCE_ROOT


def config_file(name: str) -> Path | None:
    """
    Return ``config/NAME`` in :func:`share_dir`.

    Parameters
    ----------
    name : str
        File name inside ``config/`` (e.g. ``'model_3axis.yaml'``).

    Returns
    -------
    Path or None
        The file, or None when it does not exist.

    """
    p = share_dir() / 'config' / name
    return p if p.is_file() else None
