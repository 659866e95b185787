"""Paths of the recording excerpts shipped for the tests (tests/data, see its README.md)."""

from pathlib import Path

DATA = Path(__file__).parent / "data"
#: The first 7 s of a pyshoe (VICON-referenced) recording, with truth.
PYSHOE_SAMPLE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
#: Excerpts of pyshoe recordings (.mat), the replay env's data_dir in the tests.
REPLAY_DATA = DATA / "replay"
#: Excerpts of the hallway recordings (SensorConnect CSV, footprints, LLIO .mat).
HALLWAY_DATA = DATA / "hallway"
