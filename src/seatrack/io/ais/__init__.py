"""AIS input and output: readers of CSV (common, DMA, NOAA MarineCadastre; plain or
gzip/zstd/bz2-compressed), Parquet and NMEA logs with every line accounted for, TRACKS
output as CSV or Parquet, and the bounded-memory pipeline of ``seatrack ais``.

Modules: :mod:`~seatrack.io.ais.reports` (the report table, reject reasons, validation),
:mod:`~.columnar` (pyarrow readers), :mod:`~.lines` (the line-by-line reader, CSV and NMEA
mixed), :mod:`~.nmea` (NMEA sentences), :mod:`~.read` (choosing the reader),
:mod:`~.output` (TRACKS), :mod:`~.pipeline` (memory budget, vessel groups),
:mod:`~.cluster` (Dask).
"""

from seatrack.io.ais.columnar import SCHEMAS
from seatrack.io.ais.columnar import detect_schema
from seatrack.io.ais.output import TRACK_COLUMNS
from seatrack.io.ais.output import TracksWriter
from seatrack.io.ais.output import format_times
from seatrack.io.ais.output import track_columns
from seatrack.io.ais.output import write_tracks
from seatrack.io.ais.output import write_tracks_csv
from seatrack.io.ais.pipeline import DEFAULT_MEMORY_LIMIT
from seatrack.io.ais.pipeline import RunSummary
from seatrack.io.ais.pipeline import track_files
from seatrack.io.ais.read import looks_like_nmea
from seatrack.io.ais.read import read_ais
from seatrack.io.ais.read import read_ais_csv
from seatrack.io.ais.read import read_file
from seatrack.io.ais.reports import REJECT_REASONS
from seatrack.io.ais.reports import AisReports
from seatrack.io.ais.reports import concat_reports
from seatrack.io.ais.reports import output_order
from seatrack.io.ais.reports import parse_times
from seatrack.io.ais.reports import rejection_counts
from seatrack.io.ais.reports import to_local
from seatrack.io.ais.reports import validate_reports

__all__ = [
    "AisReports",
    "DEFAULT_MEMORY_LIMIT",
    "REJECT_REASONS",
    "RunSummary",
    "SCHEMAS",
    "TRACK_COLUMNS",
    "TracksWriter",
    "concat_reports",
    "detect_schema",
    "format_times",
    "looks_like_nmea",
    "output_order",
    "parse_times",
    "read_ais",
    "read_ais_csv",
    "read_file",
    "rejection_counts",
    "track_columns",
    "to_local",
    "track_files",
    "validate_reports",
    "write_tracks",
    "write_tracks_csv",
]
