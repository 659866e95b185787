"""The foot simulator beside real recordings (docs/SIM_TO_REAL.md).

- :mod:`pednav_env.calibration.stats` — statistics of a walk (label-free
  quietness measure from the SHOE statistic, speeds, per-stride stance and
  swing signal levels);
- :mod:`pednav_env.calibration.sources` — walks from recordings, hallway
  footprint files and simulations.
"""
