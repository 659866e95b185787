"""The ZUPT-UKF on recorded walks (docs/REAL_DATA.md).

- :mod:`pednav_env.replay.setup` — :class:`RealFilterSetup`, the shipped
  setups ``paper`` and ``real-fixed``, and setup JSON files;
- :mod:`pednav_env.replay.start` — where navigation starts (the still span
  for the alignment);
- :mod:`pednav_env.replay.runner` — a :class:`pednav_env.io.Recording` through
  the filter (uniform grid, still start, mounting, alignment);
- :mod:`pednav_env.replay.stream` — the same filter online, fed samples or
  blocks as they arrive;
- :mod:`pednav_env.replay.track` — the estimated track with its covariance
  as a table (``pednav run --out``);
- :mod:`pednav_env.replay.metrics` — ARMSE, PyShoe's ARMSE, final error,
  footprint errors, loop closure;
- :mod:`pednav_env.replay.search` — the development search behind ``real-fixed``;
- :mod:`pednav_env.replay.simulate` — simulated walks written as recordings
  (``pednav simulate``).
"""
