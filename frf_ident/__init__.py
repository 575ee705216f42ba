"""
frf_ident: closed-loop FRF identification of flexible-joint robots.

Implements Saupe & Knoblach (2015), "Experimental determination of frequency response
function estimates for flexible joint industrial manipulators with serial kinematics".

Layers, bottom to top (each imports only the ones below it; contracts in .importlinter):

- ``frf_ident.errors``: the exception hierarchy.
- ``frf_ident.core``: pure numpy/scipy (model, simulation, excitation, estimation,
  diagnosis). Never imports ROS, DDS, bag, YAML or plotting libraries.
- ``frf_ident.io``: model files, CSV/MAT import, FRF export, the package's data files.
- adapters: ``frf_ident.bag`` (rosbag2 MCAP I/O), ``frf_ident.middleware`` (rclpy / Cyclone
  DDS), ``frf_ident.report`` (figures and HTML).
- ``frf_ident.app``: one application function per job, shared by CLI and nodes.
- ``frf_ident.cli`` and ``frf_ident.nodes`` on top.
"""

__all__ = ['__version__']

__version__ = '0.1.0'
