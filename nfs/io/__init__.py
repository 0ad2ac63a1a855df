"""Measurement files (``nfs-measurement/1``) and scenario files."""
