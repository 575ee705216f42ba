"""
Robot model: typed parameters and the model-file schema (no file I/O).

- :mod:`frf_ident.core.model.params` — ``AxisParams`` per joint and ``RobotParams`` of the
  arm (eqs. 1, 2, 20-22)
- :mod:`frf_ident.core.model.schema` — model-file mappings (docs/CONTRACT.md §5) to and from
  those classes, with one-line errors naming the field; YAML parsing is in
  :mod:`frf_ident.io.model_file`
"""
