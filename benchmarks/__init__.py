"""Benchmarks of frf_ident (`make bench`); not part of the installed package."""
