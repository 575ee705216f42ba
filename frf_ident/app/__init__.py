"""
Application functions used by both the CLI and the nodes: one module per job.

- :mod:`frf_ident.app.identify` — run the experiments in closed loop, record a bag
- :mod:`frf_ident.app.estimate` — estimate FRFs from a bag (in memory, or streamed by
  :mod:`frf_ident.app.stream_estimate` when it would not fit)
- :mod:`frf_ident.app.import_data` — measured CSV/MAT tables to bags
- :mod:`frf_ident.app.diagnose` — what the nominal model lacks, the extended model
- :mod:`frf_ident.app.reproduce` — the paper's Section 6 example
- :mod:`frf_ident.app.demo` and :mod:`frf_ident.app.graph` — the node graph driven end to end
- :mod:`frf_ident.app.console` — progress output
"""
