"""Files only: the measurement format (``nfs-measurement/1``) and the chamber logs brought
into it (``nfs import``), TOML helpers, atomic output, output folders and provenance."""

from .atomic import atomic_output, atomic_write_bytes, atomic_write_files, atomic_write_text
from .log_import import import_log
from .log_mapping import LogMapping, read_mapping
from .measurement import FORMAT, find_runs, read_run, read_runs, write_run
from .measurement_checks import check_columns, check_units

__all__ = ["FORMAT", "check_columns", "check_units", "find_runs", "read_run", "read_runs",
           "write_run", "import_log", "read_mapping", "LogMapping", "atomic_output",
           "atomic_write_bytes", "atomic_write_files", "atomic_write_text"]
