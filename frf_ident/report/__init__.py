"""Human reports: one self-contained report.html with PNG figures next to it."""
from .html import write_report

__all__ = ['write_report']
