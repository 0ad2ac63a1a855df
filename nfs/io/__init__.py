"""Measurement files (``nfs-measurement/1``), scenario files and atomic output."""

from .atomic import atomic_output, atomic_write_bytes, atomic_write_files, atomic_write_text
from .measurement import (FORMAT, REQUIRED_COLUMNS, Run, RunMeta, check_columns, find_runs,
                          read_run, read_runs, write_run)

__all__ = ["FORMAT", "REQUIRED_COLUMNS", "Run", "RunMeta", "check_columns", "find_runs",
           "read_run", "read_runs", "write_run", "atomic_output", "atomic_write_bytes",
           "atomic_write_files", "atomic_write_text"]
