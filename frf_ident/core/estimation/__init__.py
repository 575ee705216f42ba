"""
Estimation: FRFs from recorded data and the checks that the data support them.

- :mod:`frf_ident.core.estimation.frd` — ``FrequencyResponse``, the result object
- :mod:`frf_ident.core.estimation.spectra` — eq. 7, the BLA of eq. 14, Sec. 5.1 chirp spectra
- :mod:`frf_ident.core.estimation.described` — estimates from a Recording with experiment
  descriptors
- :mod:`frf_ident.core.estimation.detected` — estimates from data without descriptors
- :mod:`frf_ident.core.estimation.checks` — refusals: clipping, band, periods, coverage
"""
