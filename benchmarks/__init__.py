"""Benchmarks and the honesty harness of dynia: run by ``make bench``, outside the library's namespace."""
