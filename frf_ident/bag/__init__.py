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
"""rosbag2 MCAP input/output of frf_ident (see docs/bag_format.md)."""
from .info import bag_info
from .reader import read_experiment, read_recording
from .recorder import BagRecorder
from .repair import reindex
from .timing import TimingReport, TopicTiming
from .topics import BagTopics
from .writer import write_recording

__all__ = ['BagRecorder', 'BagTopics', 'TimingReport', 'TopicTiming', 'bag_info',
           'read_experiment', 'read_recording', 'reindex', 'write_recording']
