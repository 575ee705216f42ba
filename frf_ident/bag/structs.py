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
The little-endian integer layouts both binary formats of a bag use (MCAP records, CDR).

One definition each, for :mod:`.mcapio` and :mod:`.cdr`.
"""
from __future__ import annotations

import struct

__all__ = ['U16', 'U32', 'U64']

#: unsigned 16-, 32- and 64-bit integers, little-endian
U16 = struct.Struct('<H')
U32 = struct.Struct('<I')
U64 = struct.Struct('<Q')
