"""Paths of the recording excerpts shipped for the tests (tests/data, see its README.md)."""

from pathlib import Path

DATA = Path(__file__).parent / "data"
#: The first 7 s of a pyshoe (VICON-referenced) recording, with truth.
PYSHOE_SAMPLE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
#: Excerpts of pyshoe recordings (.mat), the replay env's data_dir in the tests.
REPLAY_DATA = DATA / "replay"
#: Excerpts of the hallway recordings (SensorConnect CSV, footprints, LLIO .mat).
HALLWAY_DATA = DATA / "hallway"


def write_pyshoe_excerpts(directory: Path, seconds: dict[str, float]) -> Path:
    """Write shorter excerpts of :data:`PYSHOE_SAMPLE` into ``directory``: ``NAME.mat``
    holding its first ``seconds[NAME]`` s (200 Hz), so that recordings differ."""
    import scipy.io

    source = scipy.io.loadmat(PYSHOE_SAMPLE)
    for name, s in seconds.items():
        n = int(round(200 * s))
        cut = {
            "imu": source["imu"][:n],
            "ts": source["ts"][:, :n],
            "gt": source["gt"][:n],
            "zv_vicon_opt": source["zv_vicon_opt"][:, :n],
        }
        scipy.io.savemat(directory / f"{name}.mat", cut)
    return directory
