"""Results out of the core: text and HTML summaries, pandas and xarray tables, CSV files
with a ``# name = value`` header block (the one writer the app's downloads use too)."""
from .header import read_csv, read_header, settings_lines, write_csv

__all__ = ["read_csv", "read_header", "settings_lines", "write_csv"]
