"""The foot simulator beside real recordings (docs/SIM_TO_REAL.md).

- :mod:`pednav_env.calibration.stats` — statistics of a walk (label-free
  quietness measure from the SHOE statistic, the quiet phase, speeds,
  per-stride stance and swing signal levels);
- :mod:`pednav_env.calibration.strides` — stride segmentation without
  footprints (split stances, the minimum stride) and the truth glitches that
  leave strides out;
- :mod:`pednav_env.calibration.sources` — walks from recordings (hallway
  footprint walks included) and simulations, and simulated walks as
  recordings;
- :mod:`pednav_env.calibration.false_stance` — how much of a walk's swing a
  too-high SHOE threshold calls stance;
- :mod:`pednav_env.calibration.compare` — simulator models and the per-band
  comparison of ``pednav sim2real``;
- :mod:`pednav_env.calibration.fit` — the CMA-ES fit of the calibrated model;
- :mod:`pednav_env.calibration.objective` — the distance the fit minimises;
- :mod:`pednav_env.calibration.parameters` — the fitted values and the walker
  population they give;
- :mod:`pednav_env.calibration.plots` — the comparison's figures.
"""
