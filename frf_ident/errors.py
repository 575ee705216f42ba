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
Exception hierarchy of frf_ident.

Every error a user can cause derives from :class:`FrfIdentInputError`; the CLI turns it into
one line on stderr and exit status 2. Everything else is a failure (exit 1). A refused or
stopped excitation (:class:`SafetyError`) is the user's to fix too (limits, amplitudes, a
stale sensor), so it is an input error: one line, exit 2, never a traceback.
"""

__all__ = ['BagError', 'DesignError', 'EstimationError', 'FrfIdentError', 'FrfIdentInputError',
           'MjcfError', 'ModelFileError', 'NotArmed', 'SafetyError']


class FrfIdentError(Exception):
    """Base class of all frf_ident errors."""


class FrfIdentInputError(FrfIdentError, ValueError):
    """A user mistake: bad parameter, file, field or value (CLI exit status 2)."""


class DesignError(FrfIdentInputError):
    """An excitation design parameter is out of range."""


class ModelFileError(FrfIdentInputError):
    """A model file (docs/CONTRACT.md §5) is malformed."""


class MjcfError(ModelFileError):
    """An MJCF (MuJoCo model) cannot be used as the plant or model: file, element and value."""


class BagError(FrfIdentInputError):
    """A bag cannot be read or lacks what the analysis needs."""


class EstimationError(FrfIdentInputError):
    """The data do not support the requested estimate (too few periods, band, rank...)."""


class SafetyError(FrfIdentInputError):
    """A torque or position bound would be violated; the excitation was refused or stopped."""


class NotArmed(SafetyError):
    """A run was refused because no operator armed the excitation node (docs/ros2.md)."""
