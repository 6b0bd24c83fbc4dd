"""Drivers: the command line, comparisons, sweeps, figures and reports (all I/O lives here)."""
