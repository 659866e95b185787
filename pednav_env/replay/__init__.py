"""The ZUPT-UKF on recorded walks (docs/REAL_DATA.md).

- :mod:`pednav_env.replay.setup` — :class:`RealFilterSetup` and the shipped
  setups ``paper`` and ``real-fixed``;
- :mod:`pednav_env.replay.runner` — a :class:`pednav_env.io.Recording` through
  the filter (uniform grid, still start, mounting, alignment);
- :mod:`pednav_env.replay.metrics` — ARMSE, PyShoe's ARMSE, final error,
  loop closure;
- :mod:`pednav_env.replay.search` — the development search behind ``real-fixed``.
"""
