"""
ROS 2 node suite of frf_ident (plant, controller, excitation + iteration service, estimator).

Thin nodes: they wire topics and parameters to the core objects (plant, PI, procedure phases,
ChirpIteration, BagRecorder, estimate_recording). See README_nodes.md.
"""
