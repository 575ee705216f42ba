"""
frf_ident: closed-loop FRF identification of flexible-joint robots.

Implements Saupe & Knoblach (2015), "Experimental determination of frequency response
function estimates for flexible joint industrial manipulators with serial kinematics".

Layers:
- ``frf_ident.core``: pure numpy/scipy (signals, estimation, plant models, controller,
  iteration, diagnosis). Never imports ROS, DDS or bag libraries.
- adapters: ``frf_ident.bag`` (rosbag2 MCAP I/O), ``frf_ident.middleware`` (rclpy / Cyclone DDS).
- ``frf_ident.nodes`` and ``frf_ident.cli`` on top.
"""

__version__ = '0.1.0'
