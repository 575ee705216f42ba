"""Pure numerical core of frf_ident (numpy/scipy/numba only; no ROS, DDS or bag imports)."""
