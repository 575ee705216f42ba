"""Diagnosis: what the nominal simulation gets wrong, which effect causes it, and the extended
model (docs/CONTRACT.md §7). Pure numpy/scipy; no middleware imports."""
from .common import EFFECTS, Effect, apply_effect, frf_error_db, nrmse, simulate_like  # noqa: F401
from .experiments import diagnose_experiments  # noqa: F401
from .timeseries import diagnose_timeseries  # noqa: F401
