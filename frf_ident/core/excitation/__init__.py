"""
Excitation: signal designs, experiment procedures and detection in measured data.

- :mod:`frf_ident.core.excitation.multisine` — odd random-phase multisines (Sec. 4, eqs. 8-12)
- :mod:`frf_ident.core.excitation.chirp` — exponential chirps (Sec. 5, eqs. 15, 16, 26)
- :mod:`frf_ident.core.excitation.procedures` — the Section 7 procedures as phases, and the
  chirp iteration of Sec. 5.3 (eqs. 17-19)
- :mod:`frf_ident.core.excitation.detect` — recover a multisine or chirp from a signal
"""
