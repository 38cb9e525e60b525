"""AIS input and output: readers of CSV (common, DMA, NOAA MarineCadastre; plain or
gzip/zstd/bz2-compressed), Parquet and NMEA logs with every line accounted for, TRACKS
output as CSV or Parquet, and the bounded-memory pipeline of ``seatrack ais``.

Modules: :mod:`~seatrack.io.ais.reports` (the report table, reject reasons, validation),
:mod:`~.columnar` (pyarrow readers), :mod:`~.lines` (the line-by-line reader, CSV and NMEA
mixed), :mod:`~.nmea` (NMEA sentences), :mod:`~.read` (choosing the reader),
:mod:`~.output` (TRACKS), :mod:`~.pipeline` (memory budget, vessel groups),
:mod:`~.cluster` (Dask).
"""

from seatrack.io.ais.columnar import SCHEMAS, detect_schema
from seatrack.io.ais.output import (
    TRACK_COLUMNS,
    TracksWriter,
    format_times,
    track_columns,
    write_tracks,
    write_tracks_csv,
)
from seatrack.io.ais.pipeline import DEFAULT_MEMORY_LIMIT, RunSummary, track_files
from seatrack.io.ais.read import looks_like_nmea, read_ais, read_ais_csv, read_file
from seatrack.io.ais.reports import (
    REJECT_REASONS,
    AisReports,
    concat_reports,
    output_order,
    parse_times,
    rejection_counts,
    to_local,
    validate_reports,
)

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
