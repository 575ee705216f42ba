"""
Simulation: the flexible-joint plant, its controller, the closed-loop runner, analytic FRFs.

- :mod:`frf_ident.core.simulation.plant` — the plant of eqs. 1, 2, 20-22 (numba integrator)
- :mod:`frf_ident.core.simulation.controller` — velocity PI with torque limit (Fig. 2)
- :mod:`frf_ident.core.simulation.runner` — procedures run in closed loop into a Recording
- :mod:`frf_ident.core.simulation.open_loop` — open-loop experiments of the Section 6 example
- :mod:`frf_ident.core.simulation.analytic` — closed-form FRFs of the linear robot
"""
