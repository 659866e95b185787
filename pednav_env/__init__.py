"""pednav_env — gait-aware pedestrian navigation environments.

Conventions (DESIGN.md):

- SI units inside; angles in radians; a name with another unit says it
  (``rate_hz``, ``heading_deg``). Gravity g = 9.80665 m/s² unless a paper
  says otherwise (always a parameter).
- Navigation frame: local level, x₁ east, x₂ north, x₃ up (the papers' Cx).
  Body frame: x forward, y left, z up. Gravity vector (0, 0, −g); specific
  force f = a − g_vec (at rest and level an accelerometer reads (0, 0, +g)).
- Attitude: quaternion ``q_nb`` body → navigation, scalar first; Euler yaw ψ,
  pitch θ, roll γ in paper 003's 3-2-1 order.
- Arrays are batched: walkers/episodes first, then time: ``(N, T, 3)``.
- Randomness only from ``numpy.random.Generator`` objects passed in (one
  per walker) or derived from an env's ``reset(seed=...)``.
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"

if "pednav/FootZupt-v0" not in registry:
    register(
        id="pednav/FootZupt-v0",
        entry_point="pednav_env.envs.foot_zupt:FootZuptEnv",
        vector_entry_point="pednav_env.envs.foot_zupt:FootZuptVectorEnv",
    )

if "pednav/MarkerTrack-v0" not in registry:
    register(
        id="pednav/MarkerTrack-v0",
        entry_point="pednav_env.envs.marker_track:MarkerTrackEnv",
        vector_entry_point="pednav_env.envs.marker_track:MarkerTrackVectorEnv",
    )

if "pednav/WaistStep-v0" not in registry:
    register(
        id="pednav/WaistStep-v0",
        entry_point="pednav_env.envs.waist_step:WaistStepEnv",
        vector_entry_point="pednav_env.envs.waist_step:WaistStepVectorEnv",
    )

if "pednav/FootZuptReplay-v0" not in registry:
    register(
        id="pednav/FootZuptReplay-v0",
        entry_point="pednav_env.envs.foot_replay:FootZuptReplayEnv",
        vector_entry_point="pednav_env.envs.foot_replay:FootZuptReplayVectorEnv",
    )
