"""Paths of the recording excerpts shipped for the tests (tests/data, see its README.md),
and the tiny training run the CLI tests train."""

from pathlib import Path

DATA = Path(__file__).parent / "data"
#: The first 7 s of a pyshoe (VICON-referenced) recording, with truth.
PYSHOE_SAMPLE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
#: Excerpts of pyshoe recordings (.mat), the replay env's data_dir in the tests.
REPLAY_DATA = DATA / "replay"
#: Excerpts of the hallway recordings (SensorConnect CSV, footprints, LLIO .mat).
HALLWAY_DATA = DATA / "hallway"
#: A PPO configuration for ``pednav train --config`` small enough for a test (128 steps).
TINY_PPO = """pednav/WaistStep-v0:
  n_envs: 2
  n_timesteps: 128
  n_steps: 64
  batch_size: 64
  n_epochs: 1
  policy_kwargs: {net_arch: [8]}
  checkpoint_steps: 64
"""


def tiny_train_argv(tmp_path: Path, run_dir: Path, *extra: str) -> list[str]:
    """``pednav train`` arguments for :data:`TINY_PPO` (written to ``tmp_path``) into
    ``run_dir``, then ``extra``."""
    config = tmp_path / "tiny.yml"
    config.write_text(TINY_PPO)
    argv = ["train", "pednav/WaistStep-v0", "--config", str(config), "--no-progress"]
    return [*argv, "--run-dir", str(run_dir), *extra]


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
