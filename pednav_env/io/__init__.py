"""Loaders for recorded foot-IMU data (see docs/REAL_DATA.md).

- :class:`Recording` — time (s), angular rate (rad/s), specific force (m/s²),
  optional truth position (m) or footprints, metadata, and the list of issues
  found.
- :func:`load_recording` — any format: a documented generic CSV
  (:mod:`pednav_env.io.csv_format`), the x-io Gait-Tracking CSV, the PyShoe
  ``.mat`` layout (:mod:`pednav_env.io.pyshoe`), walks with footprints: the
  ``.mat`` with ground control points and the SensorConnect CSV
  (:mod:`pednav_env.io.hallway`).
- :class:`Footprints` — truth known only at footfalls
  (:mod:`pednav_env.io.footprints`).
- :class:`LoadOptions` — what to do with duplicates, gaps, saturation, unit
  checks (:mod:`pednav_env.io.validate`).
- :func:`to_uniform` — the samples on a uniform grid for the filter.
"""

from pednav_env.io.csv_format import XIO_LAYOUT, CsvLayout, load_csv, load_xio_csv
from pednav_env.io.footprints import Footprints, read_footprints_csv
from pednav_env.io.hallway import load_gcp_mat, load_sensorconnect_csv
from pednav_env.io.load import FORMATS, detect_format, find_recordings, load_recording
from pednav_env.io.pyshoe import load_pyshoe_mat
from pednav_env.io.recording import Recording, RecordingIssue
from pednav_env.io.uniform import UniformSamples, to_uniform
from pednav_env.io.validate import LoadOptions

__all__ = [
    "FORMATS",
    "XIO_LAYOUT",
    "CsvLayout",
    "Footprints",
    "LoadOptions",
    "Recording",
    "RecordingIssue",
    "UniformSamples",
    "detect_format",
    "find_recordings",
    "load_csv",
    "load_gcp_mat",
    "load_pyshoe_mat",
    "load_recording",
    "load_sensorconnect_csv",
    "load_xio_csv",
    "read_footprints_csv",
    "to_uniform",
]
