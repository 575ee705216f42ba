"""rosbag2 MCAP input/output of frf_ident (see README_bag.md)."""
from .reader import bag_info, read_recording, reindex
from .timing import TimingReport, TopicTiming
from .topics import BagTopics
from .writer import BagRecorder, write_recording

__all__ = ['BagRecorder', 'BagTopics', 'TimingReport', 'TopicTiming', 'bag_info',
           'read_recording', 'reindex', 'write_recording']
