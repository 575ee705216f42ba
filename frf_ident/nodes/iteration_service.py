"""iteration_service: ``/frf/run_iteration`` (std_srvs/Trigger), one chirp-iteration step.

The service runs in the excitation process (it drives the excitation engine directly): this
entry point starts that process, with the nodes ``excitation_node`` and ``iteration_service``.
Start either ``excitation_node`` or ``iteration_service``, not both.
"""
from typing import Optional, Sequence

from frf_ident.nodes.excitation_node import main as _main


def main(argv: Optional[Sequence[str]] = None) -> int:
    return _main(argv)


if __name__ == '__main__':
    raise SystemExit(main())
